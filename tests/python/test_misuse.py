"""Misuse that was once accepted quietly: each now raises, with a message
that names the remedy a Python user has."""
import numpy as np
import pytest

import pdyn
from conftest import FALL, run_pdyn


@pytest.mark.parametrize("n", [2.5, 2.0, "2", np.float64(2.0), None, True, np.bool_(True)])
def test_step_count_must_be_a_whole_number(fall, n):
    with pytest.raises(TypeError) as e:
        fall.step(n)
    assert str(e.value) == f"step(n): n = {n!r} is not a whole number of steps (expected an int >= 0)"
    assert fall.steps == 0 and fall.t == 0.0  # nothing was taken


def test_step_count_as_numpy_integer_and_zero(fall):
    assert fall.step(np.int64(3)) == 3
    assert fall.step(0) == 0
    assert fall.steps == 3


def test_negative_step_count(fall):
    with pytest.raises(ValueError, match=r"^step\(n\): n = -1 is negative \(expected a number of steps >= 0\)$"):
        fall.step(-1)


@pytest.mark.parametrize("call", ["load", "loads", "plugins", "describe", "check", "sweep"])
def test_missing_plugin_folder_is_refused_as_by_the_command_line(call, tmp_path):
    missing = str(tmp_path / "no" / "such" / "folder")
    expected = (f"plugin_path: '{missing}' is no such folder "
                "(expected a folder holding plugin libraries pdyn_KIND_NAME.so)")
    calls = {
        "load": lambda: pdyn.load(FALL, plugin_path=missing),
        "loads": lambda: pdyn.loads(FALL, plugin_path=[missing]),
        "plugins": lambda: pdyn.plugins(plugin_path=missing),
        "describe": lambda: pdyn.describe("gravity", plugin_path=missing),
        "check": lambda: pdyn.check("gravity", plugin_path=missing),
        "sweep": lambda: pdyn.sweep(FALL, {"simulation.dt": [0.01]}, plugin_path=missing),
    }
    with pytest.raises(ValueError) as e:
        calls[call]()
    assert str(e.value) == expected


def test_a_file_is_not_a_plugin_folder(tmp_path):
    f = tmp_path / "plugin.so"
    f.write_text("")
    with pytest.raises(ValueError, match=r"is not a folder \(expected a folder holding plugin"):
        pdyn.load(FALL, plugin_path=f)


def test_checkpoint_remembers_what_python_added(fall, tmp_path):
    # A constraint (or force) added from Python is not in the scene's text,
    # but it is part of what a checkpoint must match: restoring into a
    # simulation without it, or with other parameters, is refused with the
    # difference, and into one with the same addition it goes on as before.
    fall.add_constraint("distance", pairs=[[0, 1]])
    fall.step(5)
    fall.save(tmp_path / "rod.ckpt")
    bare = pdyn.loads(FALL, name="fall.yaml", threads=1)
    with pytest.raises(pdyn.CheckpointError) as e:
        bare.restore(tmp_path / "rod.ckpt")
    assert str(e.value) == (
        "the checkpoint was written for a different scene (fall.yaml): added: "
        "[{kind: constraint, object: {type: distance, pairs: [[0, 1]]}}] in the checkpoint, "
        "(absent) now (expected the same scene; restore(path, force=True) restores anyway)")
    other = pdyn.loads(FALL, name="fall.yaml", threads=1)
    other.add_constraint("distance", pairs=[[1, 0]])
    with pytest.raises(pdyn.CheckpointError) as e:
        other.restore(tmp_path / "rod.ckpt")
    assert "): added[0].object.pairs[0][0]: 0 in the checkpoint, 1 now and 1 more (" in str(e.value)
    same = pdyn.loads(FALL, name="fall.yaml", threads=1)
    same.add_constraint("distance", pairs=[[0, 1]])
    same.restore(tmp_path / "rod.ckpt")
    fall.step(5)
    same.step(5)
    np.testing.assert_array_equal(same.x, fall.x)  # bit for bit


def test_the_command_line_words_it_the_same(pdyn_program, tmp_path):
    missing = str(tmp_path / "nowhere")
    r = run_pdyn(pdyn_program, "plugins", "--plugin-path", missing, cwd=tmp_path)
    assert r.returncode != 0
    assert (f"'{missing}' is no such folder (expected a folder holding plugin libraries "
            "pdyn_KIND_NAME.so)") in r.stderr


def test_checkpoint_of_another_scene_names_restore_force(fall, tmp_path):
    fall.save(tmp_path / "fall.ckpt")
    other = pdyn.loads(FALL.replace("-9.81", "-1.62"), name="moon.yaml", threads=1)
    with pytest.raises(pdyn.CheckpointError) as e:
        other.restore(tmp_path / "fall.ckpt")
    assert str(e.value) == ("the checkpoint was written for a different scene (fall.yaml): "
                            "forces[0].g[2]: -9.81 in the checkpoint, -1.62 now "
                            "(expected the same scene; restore(path, force=True) restores anyway)")
    # force=True restores it, as `pdyn run --resume --force` does: the state is
    # the checkpoint's, the forces the new scene's.
    fall.step(10)
    fall.save(tmp_path / "later.ckpt")
    other.restore(tmp_path / "later.ckpt", force=True)
    assert other.steps == 10
    np.testing.assert_array_equal(other.x, fall.x)
    np.testing.assert_array_equal(other.v, fall.v)
