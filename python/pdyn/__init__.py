"""pdyn from Python: load a scene, step it, read and write its state as
NumPy arrays, add forces (written in C++ plugins or in Python) and
constraints, sweep parameters over a process pool or a dask cluster.

    import pdyn
    sim = pdyn.load("configs/hanging_cloth.yaml", set={"simulation.duration": 0.06})
    sim.step(100)
    print(sim.t, sim.x[0], sim.energies())

docs/python.md is the guide; every name here has its docstring.
"""

import math
import operator
import os
import re
import warnings

import numpy as np

from .errors import CheckpointError, Error, PluginError, SceneError, SceneWarning, StepError
from . import _pdyn
from .sweep import sweep

#: pdyn's version, "MAJOR.MINOR.PATCH" (CHANGELOG.md), as `pdyn --version` prints it.
__version__ = _pdyn.version
#: The plugin ABI version this module's host loads (docs/plugins.md, "Versions and the ABI").
abi_version = _pdyn.abi_version

__all__ = [
    "load", "loads", "Simulation", "Force", "param", "plugins", "describe", "check",
    "CheckReport", "sweep", "Error", "SceneError", "PluginError", "StepError",
    "CheckpointError", "SceneWarning",
]


# ---------------------------------------------------------------------------
# Values as a scene would write them

def _yaml(value):
    """`value` as YAML flow text, exactly: floats keep every bit (repr),
    arrays become lists, NaN and infinities YAML's .nan and .inf."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    elif isinstance(value, np.generic):
        value = value.item()
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_yaml(str(k))}: {_yaml(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_yaml(v) for v in value) + "]"
    raise TypeError(f"{value!r}: a {type(value).__name__} has no scene form "
                    "(expected a number, bool, string, list, dict or NumPy array)")


def _item(type_name, params):
    """One `forces:`/`colliders:`/`constraints:` item: a line per key, so that a message
    names the key."""
    if not isinstance(type_name, str):
        raise TypeError(f"{type_name!r}: expected a plugin name (str)")
    return "\n".join([f"type: {_yaml(type_name)}"] +
                     [f"{k}: {_yaml(v)}" for k, v in params.items()]) + "\n"


def _overrides(set):
    """`set=` as (path, YAML value) pairs, as `pdyn run --set` takes them."""
    return [(str(k), _yaml(v)) for k, v in (set or {}).items()]


def _paths(plugin_path):
    """plugin_path= as a list of folders, each checked as `pdyn run
    --plugin-path` checks it (ValueError, with the same message)."""
    if plugin_path is None:
        return []
    if isinstance(plugin_path, (str, os.PathLike)):
        plugin_path = [plugin_path]
    paths = [os.fspath(p) for p in plugin_path]
    for p in paths:
        problem = _pdyn._plugin_folder_problem(p)
        if problem:
            raise ValueError(f"plugin_path: {problem}")
    return paths


# ---------------------------------------------------------------------------
# Loading

def load(scene, set=None, plugin_path=None, threads=0):
    """Loads a scene file, or YAML text (anything with a newline, or that is
    not the name of a file), into a Simulation ready to step.

    set: {"simulation.dt": 5e-4, "forces[0].g": [0, 0, -1.62]} -- overrides,
        as `pdyn run --set` (values are Python values).
    plugin_path: extra folders searched for plugins first.
    threads: force and solver threads; 0: the scene's, else one per 4096
        particles (at least 1, at most every core).
    Raises SceneError (with file, line, column) or PluginError."""
    overrides = _overrides(set)
    text = isinstance(scene, str) and ("\n" in scene or not os.path.exists(scene))
    if text and "\n" not in scene and re.search(r"\.ya?ml$", scene):
        raise SceneError(f"{scene}: cannot read the scene file (expected a readable YAML file)")
    core = _pdyn._load(scene if text else os.fspath(scene), text, "<string>", overrides,
                       _paths(plugin_path), int(threads))
    return Simulation(core)


def loads(text, name="<string>", set=None, plugin_path=None, threads=0):
    """Loads a scene from YAML text; `name` stands for the file in messages."""
    return Simulation(_pdyn._load(text, True, name, _overrides(set), _paths(plugin_path), int(threads)))


# ---------------------------------------------------------------------------
# The simulation

class Simulation:
    """A loaded scene. Its state arrays are views of the particle store, not
    copies: ``sim.x[3] = (0, 0, 1)`` moves particle 3. x and v are (N, 3)
    float64 and writable; mass (N,), fixed (N,) bool and f (N, 3, the forces
    of the last evaluation) are read-only (use set_masses, set_fixed,
    evaluate_forces). Adding particles replaces the store: arrays taken
    before stay readable (the old values) but become read-only; take new
    ones from the simulation."""

    def __init__(self, core):
        self._core = core
        # What the scene loaded but will not use (a data file's Bonds, ...),
        # as `pdyn validate` and `pdyn run` print it: a Python warning, raised
        # at the caller's load() or loads().
        for message in core._warnings:
            warnings.warn(message, SceneWarning, stacklevel=3)

    # ---- state ----
    def _forward(name, doc):
        """A read-only attribute of the compiled simulation, as a property."""
        return property(lambda self: getattr(self._core, name), doc=doc)

    x = _forward("x", "positions, m: (N, 3) view")
    v = _forward("v", "velocities, m/s: (N, 3) view")
    f = _forward("f", "forces of the last evaluation, N: (N, 3) read-only view")
    fixed = _forward("fixed", "nailed particles: (N,) bool, read-only")
    n = _forward("n", "number of particles")
    t = _forward("t", "simulated time, s")
    steps = _forward("steps", "steps taken")
    end_time = _forward("end_time", "the scene's end (simulation.steps * dt or duration), s")
    file = _forward("file", "the scene's file")
    solver = _forward("solver", "the solver's plugin name")
    force_evaluations = _forward("force_evaluations",
                                 "force evaluations so far (the cost measure)")
    del _forward

    @property
    def mass(self):
        """masses, kg: (N,) read-only view; assign an array to change them"""
        return self._core.mass

    @mass.setter
    def mass(self, values):
        self._core.set_masses(np.asarray(values, dtype=float))

    def set_masses(self, values):
        """Sets every particle's mass, kg (N finite values > 0)."""
        self._core.set_masses(np.asarray(values, dtype=float))

    def set_fixed(self, i, fixed=True):
        """Nails particle i in place (fixed=True zeroes its velocity), or frees it."""
        self._core.set_fixed(int(i), bool(fixed))

    @property
    def dt(self):
        """the time step, s; setting it restarts the step times at the current time"""
        return self._core.dt

    @dt.setter
    def dt(self, value):
        self._core.dt = float(value)

    # ---- stepping ----
    def step(self, n=1):
        """Takes n steps, exactly as `pdyn run` takes them (the same bits),
        with the GIL released. Raises StepError if a step fails (the
        simulation stays at the last good state) and KeyboardInterrupt on
        Ctrl-C (after the step in progress). Returns the steps taken.
        n is a whole number (an int or a NumPy integer) >= 0: step(2.5)
        raises TypeError rather than taking 2 steps, and so does a bool
        (step(True) is a mistake, not one step)."""
        try:
            if isinstance(n, (bool, np.bool_)):
                raise TypeError
            n = operator.index(n)
        except TypeError:
            raise TypeError(f"step(n): n = {n!r} is not a whole number of steps "
                            f"(expected an int >= 0)") from None
        if n < 0:
            raise ValueError(f"step(n): n = {n} is negative (expected a number of steps >= 0)")
        return self._core.step(n)

    def run(self, duration=None, every=None, callback=None):
        """Steps for `duration` seconds, or to the scene's end when None.
        With `callback`, calls callback(sim) every `every` steps (default 1)
        and at the end. Returns the steps taken."""
        target = self.end_time if duration is None else self.t + float(duration)
        if callback is None:
            return self._core._run_until(target, 2**62)
        every = 1 if every is None else int(every)
        if every < 1:
            raise ValueError(f"every = {every} (expected a number of steps >= 1)")
        taken = 0
        while True:
            k = self._core._run_until(target, every)
            taken += k
            if k == 0:
                break
            callback(self)
            if k < every:
                break
        return taken

    # ---- forces, colliders, constraints, solver ----
    def add_force(self, force, /, **params):
        """Adds a force: a plugin by name with its parameters as keywords,
        checked as in a scene (add_force("spring", ks=100, kd=0.1,
        pairs=np.array([[0, 1]]))), or an instance of a pdyn.Force subclass.
        Returns the label that names it (remove(label), energies())."""
        if isinstance(force, Force):
            if params:
                raise TypeError("add_force(instance): parameters go to the instance's constructor")
            return self._core._add_python_force(force)
        return self._core._add_plugin(_pdyn._Kind.force, _item(force, params), "add_force")

    def add_collider(self, collider, /, **params):
        """Adds a collider plugin by name (add_collider("plane", normal=[0, 0, 1]))."""
        return self._core._add_plugin(_pdyn._Kind.collider, _item(collider, params),
                                      "add_collider")

    def add_constraint(self, constraint, /, **params):
        """Adds a hard constraint: a constraint plugin by name with its
        parameters as keywords, checked as in a scene's `constraints:` list
        (add_constraint("distance", pairs=[[0, 1]]): a rod whose length is
        the current distance). Geometry a scene may leave out is taken from
        the current positions. Held by Witkin's constraint force from the
        next step on (docs/constraints.md). Returns the label that names it
        (sim.constraints); a constraint cannot be removed."""
        return self._core._add_plugin(_pdyn._Kind.constraint, _item(constraint, params),
                                      "add_constraint")

    def set_solver(self, solver, /, **params):
        """Replaces the solver (set_solver("verlet")); the step times restart now."""
        return self._core._add_plugin(_pdyn._Kind.solver, _item(solver, params), "set_solver")

    def remove(self, label):
        """Removes the force or collider with that label (a constraint cannot be
        removed: KeyError, saying so)."""
        self._core.remove(label)

    @property
    def forces(self):
        """labels of the force and collider objects, in evaluation order"""
        return self._core._labels()

    @property
    def constraints(self):
        """labels of the constraint objects, in the order they were added"""
        return self._core._constraint_labels()

    def constraint_error(self):
        """The largest |C| over every constraint row at the current state, in
        each row's unit (m for a rod): the drift a run reports; 0 without
        constraints."""
        return self._core.constraint_error()

    def evaluate_forces(self):
        """Evaluates the forces at the current state (then read sim.f)."""
        self._core.evaluate_forces()

    # ---- observables ----
    def energies(self, extra_dof=3):
        """{"kinetic": K, "potential": {label: U}, "total": K + sum U}, J.
        Forces without a potential (drag) are not listed. Also, as the energy
        writer's columns: "dof" (3 N_free - extra_dof - the independent
        constraint rows; 3 removes the total momentum, as LAMMPS), "kT"
        (2 K / dof, J), "temperature" (K), "pressure" (the virial pressure,
        Pa, with the constraint forces' virial; None in open space or when a
        force or the solver reports no virial), "reservoir" (energy
        thermostats took out, J) and "conserved" (total + reservoir). With
        constraints it evaluates the forces at the current state first."""
        e = self._core.energies(float(extra_dof))
        e["total"] = e["kinetic"] + sum(e["potential"].values())
        e["conserved"] = e["total"] + e["reservoir"]
        return e

    def kinetic_energy(self):
        """sum m v^2 / 2, J"""
        return self._core.energies()["kinetic"]

    def potential_energy(self):
        """sum of the forces' potential energies, J"""
        return sum(self._core.energies()["potential"].values())

    # ---- particles and checkpoints ----
    def add_particles(self, x, v=None, mass=1.0, fixed=False):
        """Appends particles: x (n, 3) m, v (n, 3) m/s (default 0), mass kg
        (a number or n), fixed (a bool or n). Returns their indices."""
        first = self.n
        self._core._add_particles(np.asarray(x, dtype=float), v, mass, fixed)
        return range(first, self.n)

    def save(self, path):
        """Writes a checkpoint (atomically): restore() or `pdyn run --resume`
        continues from it bit for bit."""
        self._core.save_checkpoint(os.fspath(path))

    def restore(self, path, force=False):
        """Restores a checkpoint of this scene (same particles and plugin
        objects). Raises CheckpointError if it was written for another scene;
        force=True restores one whose scene differs only in its parameters,
        as `pdyn run --resume --force` does."""
        self._core.restore_checkpoint(os.fspath(path), bool(force))

    def __repr__(self):
        return (f"<pdyn.Simulation {self.file!r}: {self.n} particles, t = {self.t:g} s, "
                f"{self.steps} steps, solver {self.solver}>")


# ---------------------------------------------------------------------------
# Forces written in Python

class param:
    """A parameter of a Python force, as pdyn.Force.parameters declares it:

        parameters = {"k": pdyn.param(1.0, unit="N s/m", doc="drag", min=0),
                      "w": pdyn.param((1, 0, 0), unit="m/s", doc="wind velocity")}

    type is inferred from the default (float: real, int: integer, bool,
    str: string, 3 numbers: vector); give it for lists ("reals", "vectors",
    "indices", "pairs", "triples", "strings") or without a default."""

    def __init__(self, default=None, unit="", doc="", type=None, min=None, max=None,
                 required=False, sample=None):
        if type is None:
            if isinstance(default, bool):
                type = "boolean"
            elif isinstance(default, int):
                type = "integer"
            elif isinstance(default, float):
                type = "real"
            elif isinstance(default, str):
                type = "string"
            elif isinstance(default, (tuple, list, np.ndarray)) and len(default) == 3:
                type = "vector"
            else:
                raise ValueError(f"pdyn.param({default!r}): cannot tell its type "
                                 "(expected type=\"real\", \"vector\", \"pairs\", ...)")
        self.default, self.unit, self.doc, self.type = default, unit, doc, type
        self.min, self.max, self.required, self.sample = min, max, required, sample


class Force:
    """Base class of forces written in Python. Implement

        def add_forces(self, x, v, mass, f): ...   # add into f, N

    x, v (N, 3), mass (N,) are read-only views and f (N, 3) the writable
    force accumulator, valid during the call only (self.t is the time, s).
    Optionally potential_energy(self, x, v, mass) -> float (J). Class
    attributes describe it as a plugin: `parameters` (name -> pdyn.param;
    the constructor receives them as keywords, and the base class's sets
    them as attributes), `internal`, `dissipative`,
    `singular`, `reads_velocity`, `reads_time` (the conformance kit checks
    each claim; set the last two False, on the class or in __init__, for a
    force of positions only, which verlet then evaluates once per step
    instead of twice), `name` (default:
    the class name in snake_case), `version`. pdyn.check(cls) runs the kit;
    a scene loaded after the class is defined may use it by name."""

    parameters = {}
    internal = False
    dissipative = False
    singular = False
    reads_velocity = True
    reads_time = True
    version = "0.1.0"
    t = 0.0

    def __init__(self, **params):
        """Sets each declared parameter as an attribute (self.k), from
        `params` or its default; a subclass with its own __init__ may call
        super().__init__(**params)."""
        declared = type(self).parameters
        for key in params:
            if key not in declared:
                raise TypeError(f"{type(self).__name__}: unknown parameter '{key}' (expected one "
                                f"of: {', '.join(declared) or 'none'})")
        for key, spec in declared.items():
            if key in params:
                setattr(self, key, params[key])
            elif spec.required and spec.default is None:
                raise TypeError(f"{type(self).__name__}: missing parameter '{key}'")
            else:
                setattr(self, key, spec.default)

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        _pdyn._register_force(cls)

    @classmethod
    def plugin_name(cls):
        name = cls.__dict__.get("name")
        if name is None:
            name = re.sub(r"(?<!^)(?=[A-Z])", "_", cls.__name__).lower()
        return name

    @classmethod
    def description(cls):
        doc = (cls.__doc__ or "").strip()
        return doc.splitlines()[0] if doc else f"Python force {cls.__qualname__}"

    def add_forces(self, x, v, mass, f):
        raise NotImplementedError(f"{type(self).__name__}.add_forces")

    def potential_energy(self, x, v, mass):
        return None


# ---------------------------------------------------------------------------
# Plugins and the conformance kit

def plugins(plugin_path=None):
    """Every plugin found: dicts of name, kind, version, description, library."""
    return _pdyn._plugins(_paths(plugin_path))


def describe(name, plugin_path=None):
    """A plugin's descriptor: name, kind, version, description, library,
    parameters (name, type, unit, doc, required, default, min, max) and,
    for a force, its traits. Raises PluginError for an unknown name."""
    return _pdyn._describe(str(name), _paths(plugin_path))


class CheckResult:
    """One conformance check: name, verdict ("pass", "FAIL", "skip"),
    measured and bound (in the check's units), detail."""

    __slots__ = ("name", "verdict", "measured", "bound", "detail")

    def __init__(self, name, verdict, measured, bound, detail):
        self.name, self.verdict, self.measured, self.bound, self.detail = (
            name, verdict, measured, bound, detail)

    @property
    def passed(self):
        return self.verdict != "FAIL"

    def __repr__(self):
        return f"<check {self.name}: {self.verdict} ({self.detail})>"


class CheckReport(list):
    """The conformance kit's results (a list of CheckResult): `passed` is
    True when no check failed; str() is the table `pdyn check` prints."""

    def __init__(self, plugin, results, table):
        super().__init__(results)
        self.plugin, self._table = plugin, table

    @property
    def passed(self):
        return all(r.passed for r in self)

    @property
    def failed(self):
        return [r for r in self if not r.passed]

    def __getitem__(self, key):
        if isinstance(key, str):
            for r in self:
                if r.name == key:
                    return r
            raise KeyError(key)
        return super().__getitem__(key)

    def __str__(self):
        return self._table


def check(plugin, plugin_path=None, seed=1):
    """Runs the conformance kit on a plugin: a name on the plugin path, a
    library file (.so), or a pdyn.Force subclass. C++ plugins run isolated
    in a child process, as under `pdyn check`."""
    target = plugin if isinstance(plugin, type) else os.fspath(plugin)
    if isinstance(target, type) and not issubclass(target, Force):
        raise TypeError(f"{target.__name__} is not a pdyn.Force subclass")
    name, rows, table = _pdyn._check(target, _paths(plugin_path), int(seed))
    return CheckReport(name, [CheckResult(*r) for r in rows], table)
