"""pdyn.sweep on a local process pool and on a dask.distributed cluster."""
import concurrent.futures
import multiprocessing

import numpy as np
import pytest

import pdyn
from pdyn.sweep import grid_of, run_variant

# A mass on a spring to a nailed particle: period T = 2 pi sqrt(m / ks).
OSCILLATOR = """
simulation: { dt: 0.001, steps: 200 }
particles:
  - { position: [0, 0, 0], mass: 1, fixed: true }
  - { position: [1.1, 0, 0], mass: 0.5 }
forces:
  - { type: spring, ks: 10, kd: 0, rest: 1, pairs: [[0, 1]] }
"""
GRID = {"forces[0].ks": [10.0, 40.0], "simulation.dt": [0.001, 0.0005]}


def final_x(sim):
    return float(sim.x[1, 0])


def test_grid_order_and_bad_grids():
    assert grid_of(GRID) == [
        {"forces[0].ks": 10.0, "simulation.dt": 0.001},
        {"forces[0].ks": 10.0, "simulation.dt": 0.0005},
        {"forces[0].ks": 40.0, "simulation.dt": 0.001},
        {"forces[0].ks": 40.0, "simulation.dt": 0.0005},
    ]
    with pytest.raises(TypeError, match=r"sweep grid\['a'\]: 3 \(expected a list of values\)"):
        grid_of({"a": 3})


def sequential():
    return [run_variant(OSCILLATOR, v, final_x) for v in grid_of(GRID)]


def test_process_pool_gives_the_sequential_results():
    with concurrent.futures.ProcessPoolExecutor(
            2, mp_context=multiprocessing.get_context("spawn")) as pool:
        results = pdyn.sweep(OSCILLATOR, GRID, extract=final_x, executor=pool)
    assert [r.params for r in results] == grid_of(GRID)
    assert [r.value for r in results] == sequential()  # bit for bit
    # The physics: x(t) = 1 + 0.1 cos(omega t), omega = sqrt(ks / m).
    for r in results:
        t = 200 * r.params["simulation.dt"]
        omega = np.sqrt(r.params["forces[0].ks"] / 0.5)
        assert r.value == pytest.approx(1 + 0.1 * np.cos(omega * t), abs=1e-9)


def test_default_executor_and_summary():
    results = pdyn.sweep(OSCILLATOR, {"forces[0].ks": [10.0, 20.0]})
    assert [r.value["steps"] for r in results] == [200, 200]
    assert results[0].value["x"].shape == (2, 3)


def test_a_failing_variant_raises_its_error():
    with pytest.raises(pdyn.SceneError, match=r"forces\[0\].ks=-1: forces\[0\].ks: -1 is out of range"):
        pdyn.sweep(OSCILLATOR, {"forces[0].ks": [10.0, -1]},
                   executor=concurrent.futures.ThreadPoolExecutor(1))


def test_dask_distributed_cluster():
    import distributed  # Debian's python3-distributed: a missing module fails the test
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        results = pdyn.sweep(OSCILLATOR, GRID, extract=final_x, executor=client)
    assert [r.value for r in results] == sequential()
