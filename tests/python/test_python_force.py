"""Forces written in Python: stepping with every solver, from a scene, and
under the conformance kit."""
import threading
import time

import numpy as np
import pytest

import pdyn
from conftest import CONFIGS, FALL


class LinearDrag(pdyn.Force):
    """linear drag f = -k v"""
    parameters = {"k": pdyn.param(0.5, unit="kg/s", doc="drag coefficient", min=0)}
    dissipative = True

    def __init__(self, k=0.5):
        self.k = k

    def add_forces(self, x, v, mass, f):
        f -= self.k * v


class Tether(pdyn.Force):
    """a zero-length spring from each particle to the origin: U = ks |x|^2 / 2"""
    parameters = {"ks": pdyn.param(2.0, unit="N/m", doc="stiffness", min=0)}

    def __init__(self, ks=2.0):
        self.ks = ks

    def add_forces(self, x, v, mass, f):
        f -= self.ks * x

    def potential_energy(self, x, v, mass):
        return 0.5 * self.ks * float(np.sum(x * x))


class WrongGradient(Tether):
    """claims U = ks |x|^2 but adds -ks x"""

    def potential_energy(self, x, v, mass):
        return self.ks * float(np.sum(x * x))


# Every solver that integrates Newton's equations as they are: a thermostat
# (nose_hoover) adds its own friction and has tests of its own.
SOLVERS = [p["name"] for p in pdyn.plugins() if p["kind"] == "solver" and p["name"] != "nose_hoover"]


@pytest.mark.parametrize("solver", SOLVERS)
def test_drag_decay_with_every_solver(solver):
    # One free particle with v0 = 1 under f = -k v: v(t) = exp(-k t / m).
    sim = pdyn.loads("""
simulation: { dt: 0.001, steps: 1000 }
particles: [ { position: [0, 0, 0], velocity: [1, 0, 0], mass: 2 } ]
""", threads=1)
    sim.set_solver(solver)
    sim.add_force(LinearDrag(k=0.5))
    sim.run()
    assert sim.t == pytest.approx(1.0, abs=1e-12)
    assert sim.v[0, 0] == pytest.approx(np.exp(-0.25), rel=2e-3)


def test_same_bits_as_the_builtin_force():
    # A Python tether and the same law written as a spring to a fixed
    # particle give identical steps: the adapter adds exactly what Python computed.
    scene = FALL.replace("forces:", "forces:\n  - { type: gravity, g: [0, 0, 0] }")
    a = pdyn.loads(scene)
    a.add_force(Tether(ks=3.0))
    a.step(50)
    b = pdyn.loads(scene)
    b.add_force(LinearDrag(k=0.0))
    b.add_force(Tether(ks=3.0))
    b.step(50)
    np.testing.assert_array_equal(a.x, b.x)


def test_python_force_in_a_scene_by_name():
    sim = pdyn.loads("""
simulation: { dt: 0.01, steps: 100 }
particles: [ { position: [1, 0, 0], mass: 1 } ]
forces: [ { type: tether, ks: 4.0 } ]
""", name="tethered.yaml")
    assert sim.forces == ["tether (tethered.yaml:4:11)"]
    sim.run()
    # Harmonic: x = cos(omega t), omega = 2 rad/s; rk4 at dt = 0.01.
    assert sim.x[0, 0] == pytest.approx(np.cos(2.0), abs=1e-8)
    assert sim.energies()["total"] == pytest.approx(2.0, rel=1e-9)


def test_python_force_parameters_are_checked():
    with pytest.raises(pdyn.SceneError, match=r"forces\[0\].ks: -1 is out of range"):
        pdyn.loads("""
simulation: { dt: 0.01, steps: 1 }
particles: [ { position: [1, 0, 0], mass: 1 } ]
forces: [ { type: tether, ks: -1 } ]
""")


def test_conformance_kit_passes_a_good_force():
    report = pdyn.check(Tether)
    assert report.passed, str(report)
    assert report.plugin == "tether"
    assert len(report) > 5


def test_conformance_kit_fails_a_broken_force_naming_the_check():
    report = pdyn.check(WrongGradient)
    assert not report.passed
    assert [r.name for r in report.failed] == ["force.gradient_of_potential"], str(report)
    # U = ks |x|^2 has the gradient 2 ks x: the kit measures |f + dU/dx| = ks |x|.
    assert report["force.gradient_of_potential"].measured > 0.1


def test_conformance_kit_on_a_cpp_plugin():
    report = pdyn.check("spring")
    assert report.passed and report.plugin == "spring"
    assert "force." in str(report)


def test_kept_views_are_refused():
    class Keeper(pdyn.Force):
        def add_forces(self, x, v, mass, f):
            self.kept = x

    sim = pdyn.loads(FALL)
    sim.add_force(Keeper())
    with pytest.raises(pdyn.StepError, match="add_forces kept a reference to one of its arrays"):
        sim.step(1)


def test_gil_is_released_while_stepping():
    sim = pdyn.load(CONFIGS / "hanging_cloth.yaml", threads=1)
    ticks = []
    stop = threading.Event()

    def counter():
        while not stop.is_set():
            ticks.append(time.perf_counter())

    thread = threading.Thread(target=counter)
    thread.start()
    time.sleep(0.05)
    start = time.perf_counter()
    sim.step(400)
    end = time.perf_counter()
    stop.set()
    thread.join()
    during = sum(1 for t in ticks if start < t < end)
    # With the GIL held the counter would not run at all during the step;
    # released, it appends about a million times a second.
    assert end - start > 0.05
    assert during > 1000, (during, end - start)


def test_base_constructor_sets_the_parameters():
    class Gust(pdyn.Force):
        """uniform force f = a m"""
        parameters = {"a": pdyn.param((1.0, 0.0, 0.0), unit="m/s^2", doc="acceleration"),
                      "on": pdyn.param(True, doc="switch")}

        def add_forces(self, x, v, mass, f):
            if self.on:
                f += np.outer(mass, self.a)

    g = Gust(a=(0.0, 2.0, 0.0))
    assert g.a == (0.0, 2.0, 0.0) and g.on is True
    with pytest.raises(TypeError, match=r"Gust: unknown parameter 'b' \(expected one of: a, on\)"):
        Gust(b=1)
    # Declared after the simulation was loaded: known by name all the same.
    sim = pdyn.loads(FALL.replace("-9.81", "0"))
    sim.add_force("gust", a=[0.0, 0.0, 3.0])
    sim.step(10)
    assert sim.v[1, 2] == pytest.approx(0.3, abs=1e-14)


class CountingTether(Tether):
    """a tether that says it reads neither velocities nor time, and counts its calls"""
    reads_velocity = False
    reads_time = False
    calls = 0

    def add_forces(self, x, v, mass, f):
        type(self).calls += 1
        f -= self.ks * x


class LyingDrag(LinearDrag):
    """linear drag that claims to read no velocity"""
    reads_velocity = False


def test_positions_only_force_is_evaluated_once_per_verlet_step():
    # The same oscillator with the claim and without: the same bits, half the calls.
    text = """
simulation: { dt: 0.01, steps: 100, solver: { type: verlet } }
particles: [ { position: [1, 0, 0], mass: 1 } ]
"""
    once, twice = pdyn.loads(text, threads=1), pdyn.loads(text, threads=1)
    once.add_force(CountingTether(ks=4.0))
    twice.add_force(Tether(ks=4.0))
    once.run()
    twice.run()
    assert once.force_evaluations == 101
    assert twice.force_evaluations == 200
    assert CountingTether.calls == 101
    assert np.array_equal(once.x, twice.x) and np.array_equal(once.v, twice.v)
    assert once.x[0, 0] == pytest.approx(np.cos(2.0), abs=1e-3)  # x(1 s) = cos(w t), w = 2


def test_conformance_kit_checks_the_dependence_claim():
    assert pdyn.check(CountingTether).passed
    report = pdyn.check(LyingDrag)
    assert [r.name for r in report.failed] == ["force.dependence"], str(report)
