"""htn: JSHOP2-compatible HTN planning, monitored plan execution on robots,
and plan transformations.

One import package. Its parts are the repository's top-level folders:

* :mod:`htn.jshop` - reads JSHOP2 domains and problems, plans (no robot, no CLI);
* :mod:`htn.executor` - task dispatcher, action state machines, outcome log;
* :mod:`htn.robot` - robot back ends: PyBullet (``sim`` extra), projection, symbolic;
* :mod:`htn.transform` - plan transformations and their evaluation (``eval`` extra);
* :mod:`htn.cli` - the ``htn`` command line (also ``python -m htn``).

The bundled example domains and problems are in :data:`EXAMPLES`.
"""
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent
"""Folder holding the bundled ``domains/`` and ``problems/``."""


def __getattr__(name):
    # the version is read from the installed metadata only when asked for
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version
        try:
            return version("htn")
        except PackageNotFoundError:
            return "0+unknown"
    raise AttributeError(f"module 'htn' has no attribute {name!r}")
