"""What ``htn run --gui`` checks before any work starts: a display PyBullet
can open a window on. (Output paths are checked by :mod:`htn.cli.output`.)"""
from __future__ import annotations

import os

import click

from htn.jshop.language.errors import HtnError


def check_display() -> None:
    """--gui needs an X server PyBullet can open a window on: check it answers
    (PyBullet itself exits without a word when it cannot)."""
    import socket       # only for --gui: not at start-up
    disp = os.environ.get("DISPLAY")
    if not disp:
        raise click.UsageError("--gui needs a display (DISPLAY is not set); run headless without it")
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
        raise HtnError(f"--gui: no X server answers on DISPLAY={disp}; run headless without --gui")
