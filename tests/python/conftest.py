"""Shared fixtures of the Python module's tests: the pdyn program, the
configs folder, and small scenes."""
import os
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
CONFIGS = ROOT / "configs"


@pytest.fixture(scope="session")
def pdyn_program():
    """The pdyn command of this build (CTest passes it as $PDYN)."""
    path = os.environ.get("PDYN")
    if not path:
        pytest.fail("PDYN is not set (expected the path of the pdyn program; CTest sets it)")
    return path


def run_pdyn(program, *args, cwd):
    return subprocess.run([program, *map(str, args)], cwd=cwd, capture_output=True, text=True)


def final_frame(csv_path):
    """The last frame of a frames CSV: (t, x (N, 3), v (N, 3)), exact
    (pdyn writes 17 significant digits, which read back bit for bit)."""
    data = np.loadtxt(csv_path, delimiter=",", skiprows=1, ndmin=2)
    last = data[data[:, 0] == data[-1, 0]]
    last = last[np.argsort(last[:, 1])]
    return last[0, 0], last[:, 2:5], last[:, 5:8]


FALL = """
simulation: { dt: 0.01, steps: 100, solver: { type: rk4 } }
particles:
  - { position: [0, 0, 1], velocity: [1, 0, 0], mass: 2 }
  - { position: [1, 0, 1], mass: 1 }
forces:
  - { type: gravity, g: [0, 0, -9.81] }
"""


@pytest.fixture
def fall():
    """Two free particles under gravity: x(t) = x0 + v0 t + g t^2 / 2."""
    import pdyn
    return pdyn.loads(FALL, name="fall.yaml", threads=1)
