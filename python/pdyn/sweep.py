"""Parameter sweeps: one scene, a grid of overrides, run on any
concurrent.futures.Executor (a process pool by default, or a
dask.distributed.Client to run across machines)."""

import concurrent.futures
import itertools
import multiprocessing
import os


class SweepResult:
    """One variant of a sweep: `params` (the overrides it ran with) and
    `value` (what `extract` returned, or the default summary)."""

    __slots__ = ("params", "value")

    def __init__(self, params, value):
        self.params, self.value = params, value

    def __repr__(self):
        return f"<SweepResult {self.params}: {self.value!r}>"


def summary(sim):
    """The default extract: final time, steps, energies and state arrays."""
    return {"t": sim.t, "steps": sim.steps, "energies": sim.energies(),
            "x": sim.x.copy(), "v": sim.v.copy()}


def run_variant(scene, overrides, extract=None, duration=None, plugin_path=None, threads=1):
    """Loads `scene` (a file or YAML text) with `overrides`, runs it to its
    end (or for `duration` s) and returns extract(sim). What every worker
    of a sweep calls; a module-level function, so executors can pickle it."""
    from . import load
    sim = load(scene, set=overrides, plugin_path=plugin_path, threads=threads)
    sim.run(duration)
    return (extract or summary)(sim)


def grid_of(grid):
    """Every combination of the grid's values, as override dicts, in the
    order itertools.product gives (the last key varies fastest)."""
    keys = list(grid)
    for key, values in grid.items():
        if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
            raise TypeError(f"sweep grid['{key}']: {values!r} (expected a list of values)")
    return [dict(zip(keys, combo)) for combo in itertools.product(*grid.values())]


def sweep(scene, grid, extract=None, executor=None, duration=None, plugin_path=None,
          threads=1):
    """Runs `scene` once per combination of `grid` ({"forces[2].ks": [...],
    "simulation.dt": [...]}: scene paths as `pdyn run --set` takes them)
    and returns a SweepResult per variant, in grid order.

    extract: a function sim -> value, called at the end of each run (it must
        be picklable: defined at a module's top level); default: summary().
    executor: any concurrent.futures.Executor, or anything with the same
        submit(fn, *args) -> future.result() interface, such as a
        dask.distributed.Client (its workers need pdyn installed and the
        scene file at the same path). Default: a process pool with one
        process per core.
    duration: simulated seconds per run (default: the scene's own end).
    threads: threads per run (default 1: the runs themselves are parallel).

    A variant that fails raises its exception (SceneError, StepError, ...)
    here, naming nothing else: check one variant with pdyn.load first."""
    if isinstance(scene, os.PathLike) or (isinstance(scene, str) and "\n" not in scene
                                         and os.path.exists(scene)):
        scene = os.path.abspath(os.fspath(scene))
    from . import _paths  # here: the package imports this module before defining it
    _paths(plugin_path)  # a missing folder is refused now, as load() refuses it, not in a worker
    variants = grid_of(grid)
    own = executor is None
    if own:
        # spawn, not fork: a child forked from a process whose OpenMP
        # threads have started cannot start its own (GNU libgomp).
        executor = concurrent.futures.ProcessPoolExecutor(
            max_workers=min(len(variants), os.cpu_count() or 1) or 1,
            mp_context=multiprocessing.get_context("spawn"))
    try:
        futures = [executor.submit(run_variant, scene, v, extract, duration, plugin_path,
                                   threads) for v in variants]
        return [SweepResult(v, f.result()) for v, f in zip(variants, futures)]
    finally:
        if own:
            executor.shutdown()
