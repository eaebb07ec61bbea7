"""htn: JSHOP2-compatible HTN planning, monitored plan execution on robots,
and plan transformations.

One import package. Its parts are the repository's top-level folders:

* :mod:`htn.jshop` - reads JSHOP2 and HDDL domains and problems, plans (no robot, no CLI);
* :mod:`htn.executor` - task dispatcher, action state machines, outcome log;
* :mod:`htn.robot` - robot back ends: PyBullet (``sim`` extra), projection, symbolic;
* :mod:`htn.transform` - plan transformations over task trees;
* :mod:`htn.evaluation` - their evaluation over many runs (``eval`` extra);
* :mod:`htn.view` - the browser view of a run or a log (``view`` extra);
* :mod:`htn.api` - the use cases, one function each (what the command line calls);
* :mod:`htn.cli` - the ``htn`` command line (also ``python -m htn``).

The bundled example domains and problems are in :data:`EXAMPLES`; the
install extras and the modules each brings are in :data:`EXTRAS`.
"""
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent
"""Folder holding the bundled ``domains/`` and ``problems/``."""

EXTRAS = {
    "sim": ("pybullet", "numpy", "PIL"),       # PyBullet robots, snapshots
    "eval": ("scipy", "matplotlib", "distributed"),   # htn evaluate: statistics, plots, Dask
    "view": ("starlette", "uvicorn", "websockets"),   # htn run --view, htn view: the browser view
}


def missing_modules(extra: str) -> list[str]:
    """The modules of an install extra that cannot be imported here."""
    from importlib.util import find_spec
    return [m for m in EXTRAS[extra] if find_spec(m) is None]


def __getattr__(name):
    # the version is read from the installed metadata only when asked for
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version
        try:
            return version("htn")
        except PackageNotFoundError:
            return "0+unknown"
    raise AttributeError(f"module 'htn' has no attribute {name!r}")
