"""Temperature and pressure from Python (sim.energies()), the same numbers
as the energy writer's columns: LAMMPS's own Lennard-Jones liquid
(tests/scenes/thermo) at step 0 and step 100."""
import csv
import math

import pdyn
from conftest import ROOT

THERMO = ROOT / "tests" / "scenes" / "thermo"


def test_energies_give_lammps_temperature_and_pressure():
    reference = {int(r["step"]): r for r in csv.DictReader(open(THERMO / "reference.thermo"))}
    sim = pdyn.load(THERMO / "thermo.yaml", set={"output": None})
    for step in (0, 100):
        if step:
            sim.step(step)
        e = sim.energies()
        lammps = reference[step]
        assert e["dof"] == 3 * 256 - 3
        assert math.isclose(e["kT"], float(lammps["temp"]), rel_tol=1e-10, abs_tol=0)
        assert math.isclose(e["pressure"], float(lammps["press"]), rel_tol=1e-10, abs_tol=0)
        assert math.isclose(e["temperature"], e["kT"] / 1.380649e-23, rel_tol=1e-15)
        assert e["reservoir"] == 0.0 and e["conserved"] == e["total"]


def test_pressure_is_none_in_open_space():
    sim = pdyn.loads("simulation: { dt: 0.01, steps: 1 }\n"
                     "particles:\n"
                     "  - { position: [0, 0, 0], mass: 1, velocity: [1, 0, 0] }\n"
                     "  - { position: [1, 0, 0], mass: 1 }\n")
    e = sim.energies(extra_dof=0)
    assert e["pressure"] is None
    assert e["dof"] == 6 and math.isclose(e["kT"], 2 * 0.5 / 6, rel_tol=1e-15)
