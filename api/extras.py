"""Optional parts of the install: a use case that needs one says so, in one line."""
from __future__ import annotations

from htn.installation import missing_modules
from htn.jshop.language.errors import HtnError


def require_extra(extra: str, what: str) -> None:
    """Raise an input error (exit 2 on the command line) naming the extra if
    its modules are absent; ``what`` names what needs it (``htn evaluate``)."""
    if missing_modules(extra):
        raise HtnError(f"{what} needs the {extra} extra: pip install 'htn[{extra}]'")


def require_robot_extra(robot: str, what: str) -> None:
    """The same for the extra the robot back end ``robot`` needs, as its
    :class:`~htn.robot.backends.Backend` records it (``pybullet``: sim)."""
    from htn.robot.backends import backends
    backend = backends().get(robot)
    if backend is not None and backend.extra:
        require_extra(backend.extra, what)
