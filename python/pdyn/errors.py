"""The exceptions pdyn raises, each carrying the message the command line
prints (``pdyn run``, ``pdyn validate``) and its parts as attributes."""


class Error(Exception):
    """Any error pdyn reports (the base of the others)."""


class SceneError(Error, ValueError):
    """The scene (or a parameter given from Python) is invalid.

    ``diagnostics`` lists every problem as (location, message, file, line,
    column); ``file``, ``line`` and ``column`` locate the first (line and
    column are None where the location is not a place in a file, e.g. a
    ``set=`` override or an ``add_force`` call)."""

    diagnostics = ()
    file = None
    line = None
    column = None


class PluginError(Error):
    """A plugin cannot be used: the message names its library file."""


class StepError(Error, ArithmeticError):
    """A step failed: a plugin object threw, or the state became NaN or
    infinite. ``label`` names the plugin object at fault ("spring
    (scene.yaml:12:5)"), ``non_finite`` tells a numerical blow-up from a
    plugin fault, ``particle`` is the first non-finite particle (or None).
    The simulation is back at the last good state."""

    label = None
    non_finite = False
    particle = None


class CheckpointError(Error):
    """A checkpoint cannot be read or does not fit the simulation."""


class SceneWarning(UserWarning):
    """The scene loaded something it will not use, as ``pdyn validate`` and
    ``pdyn run`` warn: a LAMMPS data file's Bonds, Angles, Dihedrals or
    Impropers, which pdyn does not read yet, so its particles run as free
    atoms. The message is located ("data.lmp:40:1: ...")."""
