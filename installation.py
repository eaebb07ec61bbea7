"""What this installation of htn holds: the bundled example domains and
problems (:data:`EXAMPLES`) and the install extras with the modules each
brings (:data:`EXTRAS`).

Every part of the package that needs these imports them from here, not from
the package itself, so that ``htn/__init__.py`` may import the use cases
(:mod:`htn.api`) without an import circle.
"""

from __future__ import annotations

from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent
"""Folder holding the bundled ``domains/`` and ``problems/``."""

EXTRAS = {
    "sim": ("pybullet", "numpy", "PIL"),  # PyBullet robots, snapshots
    "eval": ("scipy", "matplotlib", "distributed"),  # htn evaluate: statistics, plots, Dask
    "view": ("starlette", "uvicorn", "websockets"),  # htn run --view, htn view: the browser view
}


def missing_modules(extra: str) -> list[str]:
    """The modules of an install extra that cannot be imported here."""
    from importlib.util import find_spec

    return [m for m in EXTRAS[extra] if find_spec(m) is None]


def version() -> str:
    """htn's version, as installed (``0+unknown`` when run from a source tree
    that was never installed)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as installed

    try:
        return installed("htn")
    except PackageNotFoundError:
        return "0+unknown"
