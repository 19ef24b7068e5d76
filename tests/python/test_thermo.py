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


DIMERS = ROOT / "tests" / "scenes" / "dimers"


def test_energies_count_constraints_as_the_energy_writer_and_lammps():
    # 256 rigid dimers under verlet's RATTLE (tests/scenes/dimers): dof
    # 3 N - 3 - 256 and the pressure with the rods' virial, as LAMMPS's fix
    # rattle and the energy writer's columns.
    reference = {int(r["step"]): r for r in csv.DictReader(open(DIMERS / "reference.thermo"))}
    sim = pdyn.load(DIMERS / "dimers.yaml", set={"output": None})
    for step in (0, 100):
        if step:
            sim.step(step)
        e = sim.energies()
        lammps = reference[step]
        assert e["dof"] == 3 * 512 - 3 - 256
        assert math.isclose(e["kT"], float(lammps["temp"]), rel_tol=1e-8, abs_tol=0)
        assert math.isclose(e["pressure"], float(lammps["press"]), rel_tol=1e-8, abs_tol=0)


def test_a_spinning_rigid_dimer_has_two_degrees_of_freedom_and_no_pressure():
    # Witkin's rod tension -2 m u^2 / d balances the kinetic pressure 2 K.
    sim = pdyn.loads("simulation: { dt: 0.01, steps: 1, solver: { type: rk4 },\n"
                     "  box: { min: [0, 0, 0], max: [10, 10, 10], periodic: [true, true, true] } }\n"
                     "particles:\n"
                     "  - { position: [5.5, 5, 5], velocity: [0, 0.3, 0], mass: 2 }\n"
                     "  - { position: [4.5, 5, 5], velocity: [0, -0.3, 0], mass: 2 }\n"
                     "constraints:\n"
                     "  - { type: distance, pairs: [[0, 1]] }\n")
    e = sim.energies()
    assert e["dof"] == 2
    assert math.isclose(e["kT"], 2 * 0.3**2, rel_tol=1e-15)
    assert abs(e["pressure"]) < 1e-17
