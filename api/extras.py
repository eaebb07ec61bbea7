"""What the machine must have for a use case: an optional part of the
install, a display (``gui``). One that is missing is said in one line."""

from __future__ import annotations

import os

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


def check_display() -> None:
    """A PyBullet window (``gui``) needs an X server that answers: check it
    (PyBullet itself exits without a word when it cannot open one)."""
    import socket  # only for a window: not at start-up

    disp = os.environ.get("DISPLAY")
    if not disp:
        raise HtnError("--gui needs a display (DISPLAY is not set); run headless without it")
    host, _, rest = disp.rpartition(":")
    number = rest.split(".")[0]
    if not number.isdigit():
        raise HtnError(f"--gui: DISPLAY={disp!r} is not an X display name")
    try:
        if host in ("", "unix"):
            with socket.socket(socket.AF_UNIX) as s:
                s.settimeout(2.0)
                s.connect(f"/tmp/.X11-unix/X{number}")
        else:
            socket.create_connection((host, 6000 + int(number)), timeout=2.0).close()
    except OSError:
        raise HtnError(
            f"--gui: no X server answers on DISPLAY={disp}; run headless without --gui"
        ) from None
