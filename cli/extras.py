"""Optional parts of the install: a command that needs one says so, in one line."""
from __future__ import annotations

from importlib.util import find_spec

from htn.jshop.errors import HtnError

EXTRAS = {
    "sim": ("pybullet", "numpy", "PIL"),       # PyBullet robots, snapshots
    "eval": ("scipy", "matplotlib"),          # htn evaluate: statistics and plots
}


def missing(extra: str) -> list[str]:
    return [m for m in EXTRAS[extra] if find_spec(m) is None]


def require_extra(extra: str, what: str) -> None:
    """Raise an input error (exit 2) naming the extra if its modules are absent."""
    if missing(extra):
        raise HtnError(f"{what} needs the {extra} extra: pip install 'htn[{extra}]'")
