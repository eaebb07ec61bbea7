"""Building a ROS 2 interface package with CMake against the ROS wheels of
this Python: what a build needs (:func:`check`), the fix the wheels' CMake
files need (:func:`fix_exports`) and the build itself (:func:`run`).
:mod:`htn.ros.interfaces` decides when to build and where the result goes.

Measured on ROS 2 Jazzy's wheels (see ``/work/shared/reference/ros2.md``):
the venv holding the wheels is the ament prefix (``share/<pkg>/cmake`` is
what CMake finds), with its ``bin`` first on PATH so that CMake runs this
Python; the build tools are in the ``ros`` extra (installing is pip's job:
:func:`check` only names what is missing, in one line).

Why CMake itself and not ``colcon build``: an ament_cmake package is a CMake
project, and for one package whose dependencies are all in one prefix colcon
only runs configure, build and install (a team's workspace still builds the
same source with colcon). Calling CMake gives the same install tree (less
colcon's setup scripts, which nothing here sources) in 25 s instead of 44 s
on 2 cores, and keeps colcon out of the ``ros`` extra: colcon-core pins
``setuptools<80`` (a downgrade in the user's venv) and installs pytest with
pytest-cov, pytest-repeat and pytest-rerunfailures, plugins that every
pytest run in that venv then loads.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import time
from collections.abc import Callable
from pathlib import Path

INSTALL_HINT = "pip install 'htn[ros]'"
# what configuring an interface package needs besides rclpy: share/<name>/ in the prefix
BUILD_PACKAGES = (
    "ament_cmake",
    "ament_cmake_ros",
    "rosidl_default_generators",
    "rosidl_default_runtime",
    "python_cmake_module",
    "action_msgs",
)
# the Python modules CMake's steps run: package.xml (catkin_pkg), the code
# generators (empy, lark), the C headers of numpy
BUILD_MODULES = ("catkin_pkg", "em", "lark", "numpy")

Progress = Callable[[str], None]


class InterfaceBuildError(RuntimeError):
    """An interface package cannot be found, built or loaded; the message is
    one line saying what is missing or where the failed build's log is.
    ``missing`` lists the missing tools (empty when the build itself failed),
    so that a caller (a test) can tell a machine without compilers from a
    broken build."""

    def __init__(self, message: str, missing: tuple[str, ...] = ()):
        super().__init__(message)
        self.missing = missing


def ament_prefix() -> Path:
    """The prefix the ROS wheels installed their ``share/`` and ``lib/`` into:
    this Python's data folder (the venv's root)."""
    return Path(sysconfig.get_path("data"))


def check(distro: str, package: str, which: Callable[[str], str | None] = shutil.which) -> None:
    """Raise :class:`InterfaceBuildError` naming everything a build of
    ``package`` lacks (``distro``: the ROS distribution found, empty: none);
    ``which`` finds a program (replaced in tests)."""
    missing, hints = [], []
    if not distro:
        missing.append("ROS 2 (no ros-<distro>-rclpy wheel, ROS_DISTRO unset)")
        hints.append(INSTALL_HINT)
    prefix = ament_prefix()
    lacking = [p for p in BUILD_PACKAGES if not (prefix / "share" / p).is_dir()]
    lacking += [m for m in BUILD_MODULES if importlib.util.find_spec(m) is None]
    if lacking:
        missing.append(f"the ROS 2 build tools ({', '.join(lacking)})")
        hints.append(INSTALL_HINT)
    for names, what in (
        (("cc", "gcc"), "a C compiler (cc or gcc)"),
        (("c++", "g++"), "a C++ compiler (c++ or g++)"),
        (("cmake",), "cmake"),
        (("make",), "make"),
    ):
        if not any(which(n) for n in names):
            missing.append(what)
            hints.append("apt install build-essential cmake")
    include = Path(sysconfig.get_paths()["include"])
    if not (include / "Python.h").is_file():
        missing.append(f"the Python headers (Python.h not in {include})")
        hints.append(f"apt install python{sys.version_info.major}-dev")
    if missing:
        todo = "; ".join(dict.fromkeys(hints))
        raise InterfaceBuildError(
            f"cannot build {package}: missing {', '.join(missing)} (to install: {todo})",
            tuple(missing),
        )


_INCLUDES = re.compile(r'(INTERFACE_INCLUDE_DIRECTORIES\s+")([^"]*)(")')


def fix_exports(prefix: Path | None = None) -> list[Path]:
    """Point the wheels' ``export_*__rosidl_generator_pyExport.cmake`` files at
    this machine's Python and numpy include folders; returns the files changed.

    Why: the wheels were built in a manylinux container, and these files (9 with
    the ``ros`` extra) name its folders (``/opt/python/cp311-cp311/include/python3.11``,
    its numpy's include folder). CMake refuses an imported target whose include
    folder does not exist, so no interface package configures until they name
    folders that exist here. The files are data of the installed wheels inside
    the venv (``share/<pkg>/cmake``), so a reinstalled ``*_msgs`` wheel brings
    the old paths back: a build calls this every time. It is idempotent
    (only paths that do not exist are replaced, and only by ones that do) and
    each file is replaced atomically, so two processes may run it at once."""
    prefix = prefix or ament_prefix()
    python_include = sysconfig.get_paths()["include"]
    numpy_include = _numpy_include()
    changed = []
    for path in sorted(prefix.glob("share/*/cmake/export_*__rosidl_generator_pyExport.cmake")):
        text = path.read_text()

        def local(m: re.Match) -> str:
            parts = [_local_folder(p, python_include, numpy_include) for p in m.group(2).split(";")]
            return m.group(1) + ";".join(parts) + m.group(3)

        new = _INCLUDES.sub(local, text)
        if new != text:
            tmp = path.with_name(path.name + f".htn-{os.getpid()}")
            try:
                tmp.write_text(new)
                os.replace(tmp, path)
            except OSError as error:
                raise InterfaceBuildError(
                    f"cannot correct the ROS wheels' {path}: {error}"
                ) from error
            changed.append(path)
    return changed


def _local_folder(folder: str, python_include: str, numpy_include: str | None) -> str:
    if not folder or Path(folder).exists():
        return folder
    if re.search(r"/include/python3\.\d+t?$", folder):
        return python_include
    if "numpy" in folder and folder.endswith("include") and numpy_include:
        return numpy_include
    return folder


def _numpy_include() -> str | None:
    """numpy's C headers, found without importing numpy (1.x: core, 2.x: _core)."""
    spec = importlib.util.find_spec("numpy")
    if spec is None or not spec.submodule_search_locations:
        return None
    root = Path(next(iter(spec.submodule_search_locations)))
    for sub in ("_core/include", "core/include"):
        if (root / sub / "numpy").is_dir():
            return str(root / sub)
    return None


def run(source: Path, work: Path, say: Progress) -> int:
    """Build the package at ``source`` in the empty folder ``work``: its copy
    in ``src/``, the objects in ``build/``, the install prefix ``install/``
    and CMake's output in ``build.log``; reports the percentages through
    ``say`` and returns the first failing step's exit code (0: built)."""
    src = work / "src" / source.name
    shutil.copytree(source, src, ignore=shutil.ignore_patterns("__pycache__"))
    prefix = ament_prefix()
    scripts = sysconfig.get_path("scripts")
    env = {
        **os.environ,
        "PATH": os.pathsep.join([scripts, os.environ.get("PATH", "")]),
        "AMENT_PREFIX_PATH": str(prefix),
        "CMAKE_PREFIX_PATH": str(prefix),
    }
    env.pop("PYTHONPATH", None)  # a sourced overlay is no input
    steps = [
        [
            "cmake",
            "-S",
            str(src),
            "-B",
            str(work / "build"),
            f"-DCMAKE_INSTALL_PREFIX={work / 'install'}",
            "-DBUILD_TESTING=OFF",
            f"-DPython3_EXECUTABLE={sys.executable}",
        ],
        ["cmake", "--build", str(work / "build"), "-j", str(os.cpu_count() or 1)],
        ["cmake", "--install", str(work / "build")],
    ]
    began, shown = time.monotonic(), -1
    with open(work / "build.log", "w") as log:
        for command in steps:
            log.write("$ " + " ".join(command) + "\n")
            log.flush()
            proc = subprocess.Popen(
                command,
                cwd=work,
                env=env,
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
                errors="replace",
            )
            assert proc.stdout is not None  # stdout=PIPE
            for line in proc.stdout:
                log.write(line)
                m = re.match(r"\[\s*(\d+)%\]", line)
                if m and (int(m.group(1)) >= shown + 10 or int(m.group(1)) == 100 > shown):
                    shown = int(m.group(1))
                    say(f"building {source.name}: {shown}% ({time.monotonic() - began:.0f} s)")
            if proc.wait() != 0:
                return proc.returncode
    return 0
