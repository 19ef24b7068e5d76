"""sim.step(n) and sim.run() take pdyn run's steps, bit for bit; checkpoints
continue them bit for bit."""
import pathlib

import numpy as np
import pytest

import pdyn
from conftest import CONFIGS, FALL, final_frame, run_pdyn

SCENES = sorted(CONFIGS.glob("*.yaml"))
STEPS = 40


@pytest.mark.parametrize("scene", SCENES, ids=[s.stem for s in SCENES])
def test_bit_identical_to_pdyn_run(scene, pdyn_program, tmp_path):
    overrides = {"simulation.duration": None, "simulation.steps": STEPS}
    out = run_pdyn(pdyn_program, "run", scene, "--steps", STEPS, "--quiet", "--set",
                   "output.path=frames.csv", "--threads", 2, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    t, x, v = final_frame(tmp_path / "frames.csv")
    sim = pdyn.load(scene, set=overrides, threads=1)
    assert sim.step(STEPS) == STEPS
    assert sim.t == t
    np.testing.assert_array_equal(sim.x, x)
    np.testing.assert_array_equal(sim.v, v)
    # run() to the scene's end takes the same steps.
    again = pdyn.load(scene, set=overrides, threads=2)
    again.run()
    assert again.steps == STEPS and again.t == t
    np.testing.assert_array_equal(again.x, x)


ADAPTIVE = """
simulation: { dt: 0.01, duration: 2.05, solver: { type: rk45, rtol: 1.0e-8 } }
output: { path: frames.csv, every: 7 }
particles:
  - { position: [0, 0, 0], mass: 1, fixed: true }
  - { position: [1, 0, 0], velocity: [0, 0.8, 0], mass: 1 }
forces:
  - { type: spring, ks: 30, kd: 0.1, pairs: [[0, 1]] }
  - { type: gravity, g: [0, 0, -9.81] }
"""


@pytest.mark.parametrize("dense", [True, False])
def test_adaptive_steps_match_pdyn_run(dense, pdyn_program, tmp_path):
    text = ADAPTIVE if dense else ADAPTIVE.replace("rtol: 1.0e-8", "rtol: 1.0e-8, fixed_step: true")
    scene = tmp_path / "adaptive.yaml"
    scene.write_text(text)
    out = run_pdyn(pdyn_program, "run", scene, "--quiet", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    t, x, v = final_frame(tmp_path / "frames.csv")
    sim = pdyn.load(scene)
    sim.run()
    assert sim.t == t == 2.05
    np.testing.assert_array_equal(sim.x, x)
    np.testing.assert_array_equal(sim.v, v)


def test_duration_callback_and_every(fall):
    seen = []
    taken = fall.run(0.5, every=20, callback=lambda s: seen.append((s.steps, s.t)))
    assert taken == 50
    assert seen == [(20, 0.2), (40, 0.4), (50, 0.5)]


def test_changing_dt_restarts_the_step_times(fall):
    fall.step(10)
    fall.dt = 0.025
    fall.step(4)
    assert fall.t == 0.1 + 4 * 0.025


def test_checkpoint_continues_bit_for_bit(tmp_path):
    scene = CONFIGS / "hanging_cloth.yaml"
    overrides = {"simulation.duration": None, "simulation.steps": 60}
    a = pdyn.load(scene, set=overrides)
    a.step(30)
    a.save(tmp_path / "half.ckpt")
    a.step(30)
    b = pdyn.load(scene, set=overrides)
    b.restore(tmp_path / "half.ckpt")
    assert b.steps == 30
    b.step(30)
    assert b.t == a.t
    np.testing.assert_array_equal(b.x, a.x)
    np.testing.assert_array_equal(b.v, a.v)


def test_checkpoint_of_another_scene_is_refused(fall, tmp_path):
    fall.save(tmp_path / "fall.ckpt")
    other = pdyn.load(CONFIGS / "orbit.yaml")
    with pytest.raises(pdyn.CheckpointError, match="scene"):
        other.restore(tmp_path / "fall.ckpt")


def test_checkpoint_after_a_change_of_dt(fall, tmp_path):
    fall.step(10)
    fall.dt = 1e-4
    fall.step(3)
    fall.save(tmp_path / "c.ckpt")
    fall.step(5)
    other = pdyn.loads(FALL, name="fall.yaml", threads=1)
    other.restore(tmp_path / "c.ckpt")
    other.dt = 1e-4
    other.step(5)
    assert other.t == fall.t == pytest.approx(0.1 + 8e-4, abs=1e-15)
    np.testing.assert_array_equal(other.x, fall.x)
