"""The state as NumPy views of the particle store, and what writing into it does."""
import gc

import numpy as np
import pytest

import pdyn


def test_views_share_the_store(fall):
    x, v = fall.x, fall.v
    assert x.shape == (2, 3) and v.shape == (2, 3) and x.dtype == np.float64
    # One store, [x | v]: the velocities start 3N doubles after the positions.
    xa = x.__array_interface__["data"][0]
    assert v.__array_interface__["data"][0] == xa + 3 * 2 * 8
    assert fall.x.__array_interface__["data"][0] == xa  # a view again, not a copy
    assert np.shares_memory(x, fall.x)
    fall.step(10)
    assert x[0, 0] == fall.x[0, 0] != 0.0  # the old view sees the new state


def test_writing_a_view_moves_the_particle(fall):
    fall.x[1] = (5.0, 6.0, 7.0)
    fall.v[1] = (0.0, 0.0, 2.0)
    fall.step(1)
    dt = 0.01
    # rk4 is exact on a constant force: x = x0 + v0 dt + g dt^2 / 2.
    np.testing.assert_allclose(fall.x[1], [5.0, 6.0, 7.0 + 2.0 * dt - 9.81 * dt * dt / 2],
                               rtol=0, atol=1e-15)


def test_step_is_exact_for_a_constant_force(fall):
    fall.step(100)
    assert fall.t == 1.0 and fall.steps == 100
    np.testing.assert_allclose(fall.x[0], [1.0, 0.0, 1.0 - 9.81 / 2], rtol=0, atol=1e-12)


def test_read_only_views(fall):
    for name in ("mass", "fixed", "f"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(fall, name)[0] = 1
    fall.mass = [4.0, 1.0]
    assert fall.mass[0] == 4.0
    with pytest.raises(ValueError, match=r"mass\[1\] = -1 kg \(expected a finite mass > 0\)"):
        fall.mass = [1.0, -1.0]
    fall.set_fixed(1)
    fall.step(5)
    assert fall.fixed.tolist() == [False, True] and fall.x[1].tolist() == [1.0, 0.0, 1.0]


def test_forces_after_an_evaluation(fall):
    fall.evaluate_forces()
    np.testing.assert_array_equal(fall.f, [[0, 0, -2 * 9.81], [0, 0, -9.81]])


def test_adding_particles_makes_old_views_read_only_snapshots(fall):
    old = fall.x
    before = old.copy()
    ids = fall.add_particles([[0, 0, 3], [0, 0, 4]], mass=[1, 2])
    assert list(ids) == [2, 3] and fall.n == 4
    assert not old.flags.writeable
    np.testing.assert_array_equal(old, before)  # the old memory is alive
    with pytest.raises(ValueError, match="read-only"):
        old[0] = 1.0
    fall.step(1)
    assert fall.x.shape == (4, 3) and fall.mass.tolist() == [2.0, 1.0, 1.0, 2.0]
    del old
    gc.collect()
    fall.add_particles(np.zeros((1, 3)))  # the first store is released now
    assert fall.n == 5


def test_non_finite_state_is_refused(fall):
    fall.x[1, 2] = np.nan
    with pytest.raises(pdyn.Error,
                       match=r"particle 1 has a non-finite position \[1, 0, nan\] \(expected "
                             r"finite values: it was written from outside the simulation\)"):
        fall.step(1)
    assert fall.steps == 0


@pytest.mark.parametrize("x, message", [
    ([0, 0, 1], r"x: shape \(3,\) \(expected \(n, 3\): one row per particle; for one "
                r"particle, \[\[x, y, z\]\]\)"),
    (np.zeros((2, 2)), r"x: shape \(2, 2\) \(expected \(n, 3\): one row per particle\)"),
])
def test_bad_shapes(fall, x, message):
    with pytest.raises(ValueError, match=message):
        fall.add_particles(x)
    assert fall.n == 2


def test_bad_masses_and_flags(fall):
    with pytest.raises(ValueError, match=r"mass\[0\] = 0 kg \(expected a finite mass > 0\)"):
        fall.add_particles([[0, 0, 0]], mass=0)
    with pytest.raises(ValueError, match=r"v: expected the shape \(1, 3\) of x"):
        fall.add_particles([[0, 0, 0]], v=np.zeros((2, 3)))
    with pytest.raises(IndexError, match=r"particle 7 \(expected 0 <= i < 2\)"):
        fall.set_fixed(7)
    with pytest.raises(ValueError, match=r"dt = -1 s \(expected a finite time step > 0\)"):
        fall.dt = -1.0


def test_energies(fall):
    e = fall.energies()
    assert e["kinetic"] == 0.5 * 2 * 1.0
    (label, u), = e["potential"].items()
    assert label == "gravity (fall.yaml:7:5)"
    assert u == pytest.approx((2 + 1) * 9.81 * 1.0, rel=1e-15)  # U = m g z
    fall.step(50)
    e1 = fall.energies()
    assert e1["total"] == pytest.approx(e["total"], rel=1e-12)  # conserved: rk4 exact here
