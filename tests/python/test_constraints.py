"""Hard constraints from Python: sim.add_constraint (a constraint plugin by
name, through the scene loader's checks, as add_force) and
sim.constraint_error() (System::constraint_error, the largest |C|)."""
import math

import numpy as np
import pytest

import pdyn

PENDULUM = """
simulation: { dt: 0.001, steps: 3000, solver: { type: rk4 } }
particles:
  - { position: [0, 0, 0], mass: 1, fixed: true }
  - { position: [1, 0, 0], mass: 0.5 }
forces:
  - { type: gravity, g: [0, 0, -9.81] }
"""


def complete_elliptic_k(k):
    """K(k) by the arithmetic-geometric mean: K = pi / (2 AGM(1, sqrt(1 - k^2)));
    it converges quadratically, so 8 rounds reach the last bit."""
    a, b = 1.0, math.sqrt(1.0 - k * k)
    for _ in range(8):
        a, b = (a + b) / 2, math.sqrt(a * b)
    return math.pi / (2 * a)


def test_rod_pendulum_swings_with_the_exact_period():
    # A bob on a 1 m rod, released at rest level with the pivot (90 degrees):
    # T = 4 sqrt(L/g) K(sin 45 deg) = 2.3678419 s. The bob's x crosses 0
    # at T/4 and 3T/4, where x is linear in t (x'' = 0 at the bottom), so
    # interpolating between steps costs nothing measurable.
    sim = pdyn.loads(PENDULUM, name="pendulum.yaml", threads=1)
    label = sim.add_constraint("distance", pairs=[[0, 1]])
    assert label == "distance (add_constraint #1)"
    assert sim.constraints == [label]
    assert sim.forces == ["gravity (pendulum.yaml:7:5)"]   # a constraint is not a force
    assert sim.constraint_error() == 0.0                    # L from the current distance
    worst, crossings = 0.0, []
    x_prev, t_prev = sim.x[1, 0], sim.t
    for _ in range(3000):
        sim.step(1)
        worst = max(worst, sim.constraint_error())
        x, t = sim.x[1, 0], sim.t
        if (x > 0) != (x_prev > 0):
            crossings.append(t_prev + (t - t_prev) * x_prev / (x_prev - x))
        x_prev, t_prev = x, t
    exact = 4 * math.sqrt(1.0 / 9.81) * complete_elliptic_k(math.sin(math.pi / 4))
    assert exact == pytest.approx(2.3678419, abs=1e-7)
    assert len(crossings) == 3                               # T/4, 3T/4, 5T/4 within 3 s
    assert 2 * (crossings[1] - crossings[0]) == pytest.approx(exact, rel=1e-9)   # 1.9e-10
    assert 4 * crossings[0] == pytest.approx(exact, rel=1e-9)                    # 2.9e-10
    assert worst < 1e-9                                      # measured 2.6e-10 m
    # The rod does no work: K + U stays 0 (measured 1.8e-9 J of 4.8 J).
    assert abs(sim.energies()["total"]) < 1e-8


def test_free_rod_falls_and_spins_rigidly(fall):
    # Two free particles (2 kg at x = 0 moving along y at 1 m/s, 1 kg at
    # x = 1 m) joined by a rod: the rod's force is internal, so the centre
    # of mass falls as a free particle, (1/3, 2/3 t, 1 - g t^2/2), while the
    # rod spins about it at 1 rad/s at its length.
    fall.v[0] = (0.0, 1.0, 0.0)          # across the rod: C' = 0 at the start
    fall.add_constraint("distance", pairs=[[0, 1]])
    worst = 0.0
    for _ in range(100):
        fall.step(1)
        worst = max(worst, fall.constraint_error())
    t = fall.t
    assert t == pytest.approx(1.0, abs=1e-12)
    com = (2 * fall.x[0] + fall.x[1]) / 3
    np.testing.assert_allclose(com, [1 / 3, 2 / 3 * t, 1 - 9.81 * t * t / 2], rtol=0, atol=1e-13)
    assert worst < 5e-12                                     # measured 6.9e-13 m at dt = 10 ms
    assert np.linalg.norm(fall.x[0] - fall.x[1]) == pytest.approx(1.0, abs=5e-12)


def test_bad_parameters_are_refused_as_in_a_scene(fall):
    cases = [
        (("distanse",), {},
         "add_constraint #1: constraint.type: unknown constraint type 'distanse' (did you mean "
         "'distance'? expected one of: bending, distance, on_circle, on_plane, on_sphere, pin)"),
        (("gravity",), {},
         "add_constraint #2: constraint.type: 'gravity' is a force plugin, not a constraint "
         "(expected one of: bending, distance, on_circle, on_plane, on_sphere, pin)"),
        (("distance",), {"pairs": [[0, 5]]},
         "add_constraint #3: constraint.pairs[0][1]: particle index 5 is out of range "
         "(expected 0..1: the scene has 2 particles)"),
        (("distance",), {"pairs": [[0, 1]], "lenght": 1.0},
         "add_constraint #4: unknown key 'lenght' in constraint (did you mean 'length'? "
         "expected one of: pairs, triples, length, types, type, compliance)"),
        # A factory's refusal (ParamError), located as the loader's own.
        (("on_sphere",), {"ids": [1], "center": [1, 0, 1]},
         "add_constraint #5: constraint.ids[0]: particle 1 is at the sphere's centre (expected "
         "it away from center: the radius is its initial distance from the centre)"),
    ]
    for args, params, message in cases:
        with pytest.raises(pdyn.SceneError) as e:
            fall.add_constraint(*args, **params)
        assert str(e.value) == message
        assert e.value.line is None      # an add_constraint call has no place in a file
    with pytest.raises(TypeError, match="has no scene form"):
        fall.add_constraint("distance", pairs=object())
    with pytest.raises(TypeError, match="expected a plugin name"):
        fall.add_constraint(3)
    assert fall.constraints == [] and fall.constraint_error() == 0.0   # nothing was added
    fall.step(5)                                            # and the fall is untouched
    assert fall.x[1, 2] == pytest.approx(1 - 9.81 * 0.05 ** 2 / 2, abs=1e-14)


def test_a_constraint_cannot_be_removed(fall):
    label = fall.add_constraint("on_plane", ids=[0, 1], normal=[0, 0, 1])
    with pytest.raises(KeyError) as e:
        fall.remove(label)
    assert e.value.args[0] == (
        "'on_plane (add_constraint #1)' is a constraint, which cannot be removed (expected the "
        "label of a force or collider: gravity (fall.yaml:7:5))")
    # Held on the plane z = 1 against gravity: the particles slide along x.
    fall.step(10)
    np.testing.assert_allclose(fall.x[:, 2], [1.0, 1.0], rtol=0, atol=1e-12)
    assert fall.x[0, 0] == pytest.approx(0.1, abs=1e-12)
