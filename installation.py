"""What this installation of htn holds: the bundled example domains and
problems (:data:`EXAMPLES`) and the install extras with the modules each
brings (:data:`EXTRAS`).

Every part of the package that needs these imports them from here, not from
the package itself, so that ``htn/__init__.py`` may import the use cases
(:mod:`htn.api`) without an import circle.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from pathlib import Path

EXAMPLES_DIR = os.path.dirname(os.path.realpath(__file__))
"""Folder holding the bundled ``domains/`` and ``problems/``, as text."""


def __getattr__(name: str) -> Path:
    # EXAMPLES, the same folder as a Path: pathlib is imported when it is
    # asked for, not by htn plan (its import costs a tenth of a small plan)
    if name == "EXAMPLES":
        from pathlib import Path

        return Path(EXAMPLES_DIR)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
