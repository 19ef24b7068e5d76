"""Python threads and one simulation (issue 42): every call into a simulation
holds it for the whole call, so threads that step, read and change one
simulation at once are served one after another, never at once; a call
from inside a call on the same thread is refused. Distinct simulations
still step in parallel with the GIL released."""
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import pdyn

# A hanging chain of springs under gravity and drag: many particles, so that
# a step takes long enough for the threads to overlap, and every force and
# the solver's scratch memory are touched by each step.
CHAIN = """
simulation: { dt: 0.001, steps: 100000, solver: { type: rk4 }, threads: 1 }
particles:
  - chain: { from: [0, 0, 0], to: [2, 0, 0], n: 200, mass: 0.01, pin: [0],
             springs: { ks: 50, kd: 0.01 } }
forces:
  - { type: gravity }
  - { type: drag, k: 0.01 }
"""

THREADS, ROUNDS, STEPS = 8, 200, 5


def test_eight_threads_stepping_one_simulation_equal_one_thread_stepping_it():
    """8 threads x 200 rounds of step(5): no crash, every step taken once,
    and the state bit for bit that of 8000 steps on one thread (the steps
    are serialized, and a fixed step's result does not depend on who calls
    it)."""
    sim = pdyn.loads(CHAIN)
    start = threading.Barrier(THREADS)

    def worker():
        start.wait()
        for _ in range(ROUNDS):
            assert sim.step(STEPS) == STEPS

    with ThreadPoolExecutor(THREADS) as pool:
        for f in [pool.submit(worker) for _ in range(THREADS)]:
            f.result()
    total = THREADS * ROUNDS * STEPS
    assert sim.steps == total
    serial = pdyn.loads(CHAIN)
    serial.step(total)
    assert serial.t == sim.t
    np.testing.assert_array_equal(sim.x, serial.x)
    np.testing.assert_array_equal(sim.v, serial.v)


def test_threads_mixing_every_call_never_corrupt_the_simulation(tmp_path):
    """Stepping, reading views, energies, forces, constraint errors, adding
    and removing forces and particles, checkpoints, all at once from 6
    threads: every call completes and the simulation still steps."""
    sim = pdyn.loads(CHAIN)
    errors = []
    start = threading.Barrier(6)

    def guarded(body):
        def run():
            start.wait()
            try:
                for k in range(40):
                    body(k)
            except Exception as e:  # pragma: no cover - reported below
                errors.append(repr(e))

        return run

    def stepper(k):
        sim.step(3)

    def reader(k):
        assert sim.x.shape == (sim.n, 3) or sim.x.shape[1] == 3
        assert np.isfinite(sim.energies()["kinetic"])
        sim.evaluate_forces()
        assert sim.constraint_error() == 0.0

    def changer(k):
        label = sim.add_force("gravity", g=[0, 0, -1])
        sim.remove(label)

    def adder(k):
        if k % 10 == 0:
            sim.add_particles([[0.0, 1.0, float(k)]], mass=0.01)

    def saver(k):
        if k % 8 == 0:
            path = tmp_path / f"c{k}.ckpt"
            sim.save(path)

    def timer(k):
        assert sim.t >= 0 and sim.steps >= 0 and sim.dt == 0.001

    bodies = [stepper, reader, changer, adder, saver, timer]
    threads = [threading.Thread(target=guarded(b)) for b in bodies]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert sim.steps == 120
    assert sim.n == 204
    assert sim.step(10) == 10
    assert np.isfinite(sim.x).all()


def test_a_python_force_calling_into_its_own_simulation_is_refused():
    """A call from inside a step on the same thread would change the state
    under the step (or wait for itself): it raises, naming the call."""
    sim = pdyn.loads(CHAIN)
    seen = []

    class Meddler(pdyn.Force):
        def add_forces(self, x, v, mass, f):
            try:
                sim.step(1)
            except RuntimeError as e:
                seen.append(str(e))

    sim.add_force(Meddler())
    sim.step(1)
    assert seen, "the force was called"
    assert seen[0] == (
        "step: called from inside another call into the same simulation on this thread (a "
        "Python force or callback cannot step, change or read the simulation that is calling "
        "it; expected the call after the step returns)")
    # The step that was running finished, and the simulation still steps.
    assert sim.steps == 1
    assert sim.step(2) == 2


def test_distinct_simulations_step_in_parallel_with_their_own_results():
    """Four simulations on four threads: each ends exactly as it does alone,
    and they overlap in time (each step releases the GIL)."""
    sims = [pdyn.loads(CHAIN, set={"forces[1].k": 0.01 * (k + 1)}) for k in range(4)]
    alone = [pdyn.loads(CHAIN, set={"forces[1].k": 0.01 * (k + 1)}) for k in range(4)]
    for s in alone:
        s.step(400)
    with ThreadPoolExecutor(4) as pool:
        list(pool.map(lambda s: s.step(400), sims))
    for s, a in zip(sims, alone):
        np.testing.assert_array_equal(s.x, a.x)
        np.testing.assert_array_equal(s.v, a.v)


def test_a_waiting_thread_does_not_hold_the_gil():
    """While one thread steps a long run, another thread waiting for the
    same simulation does not stop the rest of Python: a third thread keeps
    counting."""
    sim = pdyn.loads(CHAIN)
    counted = []
    done = threading.Event()

    def count():
        n = 0
        while not done.is_set():
            n += 1
        counted.append(n)

    def long_step():
        sim.step(3000)

    def waiting_step():
        sim.step(1)

    a = threading.Thread(target=long_step)
    b = threading.Thread(target=waiting_step)
    c = threading.Thread(target=count)
    a.start()
    b.start()
    c.start()
    a.join()
    b.join()
    done.set()
    c.join()
    assert sim.steps == 3001
    assert counted[0] > 1000
