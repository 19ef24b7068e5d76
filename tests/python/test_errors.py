"""Bad input: Python exceptions with the command line's located messages."""
import math
import os

import pytest

import pdyn
from conftest import CONFIGS

BAD = """simulation: { dt: 0.01, steps: 10 }
particles:
  - { position: [0, 0, 0], mass: 1 }
forces:
  - { type: gravity, g: [0, 0, -9.81], gg: 1 }
"""


def test_scene_error_carries_file_line_column(tmp_path):
    scene = tmp_path / "bad.yaml"
    scene.write_text(BAD)
    with pytest.raises(pdyn.SceneError) as e:
        pdyn.load(scene)
    assert (e.value.file, e.value.line, e.value.column) == (str(scene), 5, 40)
    assert str(e.value) == (f"{scene}:5:40: unknown key 'gg' in forces[0] (did you mean 'g'? "
                            "expected one of: g, group, ids, type)")
    (d,) = e.value.diagnostics
    assert d[2:] == (str(scene), 5, 40)


def test_yaml_text_and_overrides():
    with pytest.raises(pdyn.SceneError) as e:
        pdyn.loads(BAD.replace(", gg: 1", ""), name="text.yaml", set={"simulation.dt": -1})
    assert e.value.line is None  # an override has no place in the file
    assert str(e.value).startswith("--set simulation.dt=-1: simulation.dt: -1 is out of range")


def test_missing_file():
    with pytest.raises(pdyn.SceneError, match=r"nowhere.yaml: cannot read the scene file "
                                              r"\(expected a readable YAML file\)"):
        pdyn.load("nowhere.yaml")


def test_unknown_plugin_and_keyword(fall):
    with pytest.raises(pdyn.SceneError) as e:
        fall.add_force("sprng", ks=1)
    # The list goes on with the Python forces other tests declared.
    assert str(e.value).startswith(
        "add_force #1: force.type: unknown force type 'sprng' (did you mean 'spring'? expected "
        "one of: anchor, angle, angle_cosine_squared, area, attractor, dihedral, "
        "dihedral_harmonic, dihedral_opls, drag, fene, field, gravity, improper_harmonic, "
        "langevin, lennard_jones, ")
    with pytest.raises(pdyn.SceneError, match=r"unknown key 'kd' in force \(did you mean 'k'\?"):
        fall.add_force("drag", kd=0.1)
    with pytest.raises(pdyn.PluginError, match=r"unknown plugin 'nope' \(expected one of: "):
        pdyn.describe("nope")
    assert len(fall.forces) == 1  # nothing was added


def test_parameter_values_are_checked_as_in_a_scene(fall):
    with pytest.raises(pdyn.SceneError, match=r"force.ks: -1 is out of range \(expected a "
                                              r"number >= 0 in N/m\)"):
        fall.add_force("spring", ks=-1, pairs=[[0, 1]])
    with pytest.raises(pdyn.SceneError, match=r"force.pairs\[0\]\[1\]: particle index 5 is out "
                                              r"of range"):
        fall.add_force("spring", ks=1, pairs=[[0, 5]])
    with pytest.raises(TypeError, match="has no scene form"):
        fall.add_force("spring", ks=object())


def test_add_force_by_name_then_remove(fall):
    label = fall.add_force("spring", ks=100.0, kd=0.0, pairs=[[0, 1]])
    assert label == "spring (add_force #1)"
    assert label in fall.energies()["potential"]
    fall.remove(label)
    with pytest.raises(KeyError, match="no force or collider is labelled"):
        fall.remove(label)


def test_plugin_fault_names_the_force_and_keeps_the_last_good_state(fall):
    class Boom(pdyn.Force):
        def add_forces(self, x, v, mass, f):
            if self.t > 0.045:
                raise RuntimeError("boom")

    label = fall.add_force(Boom())
    with pytest.raises(pdyn.StepError) as e:
        fall.step(10)
    assert e.value.label == label and not e.value.non_finite
    assert "boom" in str(e.value) and f"plugin {label}" in str(e.value)
    assert fall.steps == 4 and fall.t == pytest.approx(0.04, abs=1e-15)


def test_non_finite_force_is_named(fall):
    class Nan(pdyn.Force):
        def add_forces(self, x, v, mass, f):
            f[1, 0] += float("nan") if self.t > 0.026 else 0.0

    label = fall.add_force(Nan())
    with pytest.raises(pdyn.StepError) as e:
        fall.step(5)
    assert e.value.non_finite and e.value.label == label
    assert "is kept: the simulation is at it" in str(e.value)
    assert fall.steps == 2


def test_solver_change(fall):
    fall.set_solver("verlet")
    assert fall.solver == "verlet"
    with pytest.raises(pdyn.SceneError, match="is a force plugin, not a solver"):
        fall.set_solver("gravity")
    fall.step(10)


PERPENDICULAR = """
simulation: { dt: 0.001, steps: 1 }
particles:
  - { position: [0, 1, 0], mass: 1 }
  - { position: [0, 0, 0], mass: 1 }
  - { position: [1, 0, 0], mass: 1 }
  - { position: [1, 0, 1], mass: 1 }
"""


def test_bonded_quads_and_types_from_python():
    # Planes at right angles: phi = pi/2; rest pi, so each term has
    # U = k/2 (pi/2)^2, with k 2 for type 0 and 6 for type 1 (docs/bonded.md).
    sim = pdyn.loads(PERPENDICULAR, name="hinge.yaml", threads=1)
    label = sim.add_force("dihedral", quads=[[0, 1, 2, 3], [3, 2, 1, 0]], types=[0, 1],
                          k=[2, 6], rest=math.pi)
    assert sim.energies()["potential"][label] == pytest.approx(8 * (math.pi / 2) ** 2 / 2,
                                                               rel=1e-14)
    with pytest.raises(pdyn.SceneError, match=r"force.types\[0\]: 2 is not a term type "
                                              r"\(expected 0..1: k, kd give 2 types\)"):
        sim.add_force("dihedral", quads=[[0, 1, 2, 3]], types=[2], k=[2, 6])


DIMER_DATA = """LAMMPS data file: two bonded atoms

2 atoms
1 bonds
1 atom types
1 bond types

0 10 xlo xhi
0 10 ylo yhi
0 10 zlo zhi

Masses

1 1.0

Atoms # bond

1 1 1 4.5 5 5
2 1 1 5.5 5 5

Bonds

1 1 1 2
"""


def test_unread_topology_is_a_located_warning(tmp_path):
    """A data file's Bonds that no force of the scene takes (issue 42): a
    SceneWarning with the command line's located message, not silence."""
    data = tmp_path / "dimer.data"
    data.write_text(DIMER_DATA)
    text = (f"simulation: {{ dt: 0.001, steps: 1, box: {{ file: {data} }}, "
            f"solver: {{ type: verlet }} }}\nparticles:\n  - {{ file: {data} }}\n")
    with pytest.warns(pdyn.SceneWarning) as caught:
        sim = pdyn.loads(text)
    assert [str(w.message) for w in caught] == [
        f"{data}:21:1: Bonds (1 row) is not read: no force or constraint of the scene takes "
        "them, so these particles run without those terms (give the scene the forces or "
        "constraints they stand for, e.g. pairs: { file: dimer.data } for the Bonds)"]
    assert caught[0].filename == __file__
    assert sim.n == 2


def test_an_interpreter_beside_another_installation_uses_only_its_own_plugins(
        tmp_path, pdyn_program):
    """A python3 whose ../lib/pdyn/plugins holds another installation's
    plugins (Debian's python3 with the pdyn packages, importing a build
    tree's module; issue 42): the module searches its own installation's
    folder only, so the other gravity is neither loaded nor a duplicate."""
    import pathlib
    import shutil
    import subprocess
    import sys

    build = pathlib.Path(pdyn_program).resolve().parents[1]
    (tmp_path / "bin").mkdir()
    plugins = tmp_path / "lib" / "pdyn" / "plugins"
    plugins.mkdir(parents=True)
    python = tmp_path / "bin" / "python3"
    shutil.copy2(os.path.realpath(sys.executable), python)
    shutil.copy2(build / "tests" / "fixtures" / "dup" / "pdyn_force_gravity.so", plugins)
    script = (
        "import pdyn\n"
        "libs = {p['name']: p['library'] for p in pdyn.plugins()}\n"
        "print(libs['gravity'])\n"
        "sim = pdyn.loads('simulation: { dt: 0.01, steps: 1 }\\n"
        "particles: [{ position: [0, 0, 0], mass: 1 }]\\n"
        "forces: [{ type: gravity }]\\n')\n"
        "sim.step(1)\n"
        "print(sim.v[0, 2])\n")
    env = {k: v for k, v in os.environ.items() if k != "PDYN_PLUGIN_PATH"}
    r = subprocess.run([str(python), "-c", script], env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    library, vz = r.stdout.split()
    assert pathlib.Path(library).resolve().parent == (build / "lib" / "pdyn" / "plugins").resolve()
    assert abs(float(vz) + 9.81 * 0.01) <= 1e-15
