"""What ``htn run`` checks before any work starts (output paths, the display
for ``--gui``)."""
from __future__ import annotations

import os

import click

from htn.jshop.errors import HtnError


def check_display() -> None:
    """--gui needs an X server PyBullet can open a window on: check it answers
    (PyBullet itself exits without a word when it cannot)."""
    import socket
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


def check_writable_file(path: str, option: str) -> None:
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise HtnError(f"{option}: no such folder {folder}", path)
    if os.path.isdir(path):
        raise HtnError(f"{option}: {path} is a folder")
    _probe(folder, option)


def check_folder(path: str, option: str) -> None:
    if os.path.exists(path) and not os.path.isdir(path):
        raise HtnError(f"{option}: {path} is not a folder")
    existing = os.path.abspath(path)
    while not os.path.exists(existing):
        existing = os.path.dirname(existing)
    if not os.path.isdir(existing):
        raise HtnError(f"{option}: cannot make a folder under {existing}, which is a file")
    _probe(existing, option)


def _probe(folder: str, option: str) -> None:
    """Can files be created in ``folder``? (Asked by creating one: permission
    bits say nothing to root, read-only file systems say it only then.)"""
    import tempfile
    try:
        tempfile.TemporaryFile(dir=folder, prefix=".htn-").close()
    except OSError as exc:
        raise HtnError(f"{option}: cannot write in {folder}: {exc.strerror or exc}")


def make_folder(path: str, option: str) -> None:
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as exc:
        raise HtnError(f"{option}: cannot make the folder {path}: {exc.strerror or exc}")
    _probe(path, option)
