"""Finding, or building once, the ROS 2 interface packages htn ships:
``htn_interfaces`` (the types of htn's nodes) and ``nav2_msgs`` (Nav2's
``NavigateToPose`` alone, as Jazzy defines it, for where Nav2 is not installed).

A package's source (``interfaces/<package>/``: ``package.xml``,
``CMakeLists.txt`` and the ``.msg``/``.srv``/``.action`` files) is a real ROS
package that a team builds in its colcon workspace; when a build of it is
importable (the workspace sourced, or a ROS install with Nav2), :func:`locate`
uses it. For pip users, :func:`build` builds it once with CMake against the ROS
wheels of this Python (the ``ros`` extra) into a per-user cache, keyed by the
ROS distribution, the Python version and a hash of the package's source, so
that a changed ``.msg`` is rebuilt and two Pythons never share compiled code::

    ~/.cache/htn/ros/jazzy-py311/<package>-<hash>/install   ($XDG_CACHE_HOME, $HTN_ROS_CACHE)

How CMake is run against the wheels is :mod:`htn.ros.cmake`'s; this module
decides when to build and where the result goes. A build happens in a
temporary folder beside its final place and is renamed into it once it has
succeeded, so a half-built package is never used; a lock file makes a second
process wait for the first one's build and then use it. Errors
(:class:`InterfaceBuildError`) are one line naming what is missing (a C or
C++ compiler, cmake, make, ``Python.h``, the build tools) or the log of the
failed build.

Making the build usable in a running process (:func:`activate`): the generated
Python modules need the package's shared libraries (type supports), and the
dynamic loader reads ``LD_LIBRARY_PATH`` only when a process starts (the
wheels' ``ros_wheels_bootstrapper`` re-executes the interpreter once to set it
for the wheels' own libraries). Rather than re-executing the caller a second
time, :func:`activate` loads the package's libraries with
``ctypes.CDLL(..., RTLD_GLOBAL)`` before the first import: the loader then
resolves the Python extension's dependencies, and the type-support dispatch's
``dlopen`` by library name, to the copies already loaded (measured: the Python
path alone fails with ``UnsupportedTypeSupport``; with the preload, services,
actions and topics work across processes). Child processes get the classic
environment instead (PYTHONPATH, LD_LIBRARY_PATH, AMENT_PREFIX_PATH), which
:func:`activate` returns. Nothing here imports rclpy.
"""

from __future__ import annotations

import ctypes
import fcntl
import functools
import hashlib
import importlib
import importlib.util
import os
import re
import shutil
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace

from . import cmake
from .cmake import InterfaceBuildError, Progress

PACKAGE = "htn_interfaces"
SOURCES = Path(__file__).resolve().parent / "interfaces"
"""The packages' sources, as shipped (a team copies or links them into its workspace)."""
SOURCE = SOURCES / PACKAGE
SHIPPED = ("htn_interfaces", "nav2_msgs")

PY = f"python{sys.version_info.major}.{sys.version_info.minor}"


# --- where: the distribution, the cache, an importable workspace build --------


def distro() -> str:
    """The ROS distribution: ``$ROS_DISTRO`` (set by a sourced ROS), else the
    one of the installed ``ros-<distro>-rclpy`` wheel; empty when neither."""
    return os.environ.get("ROS_DISTRO") or _wheel_distro()


@functools.cache
def _wheel_distro() -> str:
    """The ``<distro>`` of an installed ``ros-<distro>-rclpy`` metapackage,
    from its ``.dist-info`` folder's name (reading every installed package's
    metadata instead takes 70 ms with the wheels' 170 packages)."""
    for entry in sys.path:
        for info in Path(entry or ".").glob("ros_*_rclpy-*.dist-info"):
            m = re.fullmatch(r"ros_([a-z]+)_rclpy", info.name.split("-")[0].lower())
            if m:
                return m.group(1)
    return ""


def source_hash(package: str = PACKAGE) -> str:
    """A hash of the package's source files (names and contents): a changed
    type is a new cache entry, never a stale build."""
    digest = hashlib.sha256()
    root = SOURCES / package
    for path in _source_files(root):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def _source_files(root: Path) -> list[Path]:
    return sorted(p for p in root.rglob("*") if p.is_file() and "__pycache__" not in p.parts)


def cache_root() -> Path:
    """``$HTN_ROS_CACHE`` (tests, CI), else ``$XDG_CACHE_HOME/htn/ros``, else
    ``~/.cache/htn/ros``."""
    if os.environ.get("HTN_ROS_CACHE"):
        return Path(os.environ["HTN_ROS_CACHE"]).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "htn" / "ros"


def cache_dir() -> Path:
    """The cache of this ROS distribution and Python version (``jazzy-py311``)."""
    name = distro() or "unknown"
    return cache_root() / f"{name}-py{sys.version_info.major}{sys.version_info.minor}"


def cached_install(package: str = PACKAGE) -> Path:
    """Where :func:`build` puts (or has put) the install of the current source."""
    return cache_dir() / f"{package}-{source_hash(package)}" / "install"


def workspace_prefix(package: str = PACKAGE) -> Path | None:
    """The install prefix of an importable ``package`` (a sourced colcon
    workspace, or a build already activated in this process), else None. The
    package lives in ``<prefix>/lib/pythonX.Y/site-packages/<package>``."""
    spec = importlib.util.find_spec(package)
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(next(iter(spec.submodule_search_locations))).resolve().parents[3]


def locate(package: str = PACKAGE) -> Path | None:
    """The install prefix to use: an importable workspace build first, else the
    cache's build of the current source; None when neither exists yet."""
    found = workspace_prefix(package)
    if found is not None:
        return found
    cached = cached_install(package)
    return cached if cached.is_dir() else None


def available(package: str = PACKAGE) -> bool:
    """True when ``package`` can be used without building it."""
    return locate(package) is not None


# --- the build --------------------------------------------------------------------


def check(which=shutil.which, package: str = PACKAGE) -> None:
    """Raise :class:`InterfaceBuildError` naming everything a build lacks
    here (see :func:`htn.ros.cmake.check`)."""
    cmake.check(distro(), package, which)


def build(progress: Progress | None = None, package: str = PACKAGE) -> Path:
    """The install prefix of the current source in the cache, built with
    CMake first when it is not there (about 25 s on 2 cores, once); a no-op
    when it is. ``progress`` receives one-line messages."""
    say = progress or (lambda message: None)
    target = cached_install(package)
    if target.is_dir():
        return target
    check(package=package)
    home = target.parent.parent
    home.mkdir(parents=True, exist_ok=True)
    with _locked(home / ".lock", say, package):
        if target.is_dir():  # built by the process we waited for
            return target
        for stale in home.glob(".build-*"):  # left by a process that died building
            shutil.rmtree(stale, ignore_errors=True)
        cmake.fix_exports()
        work = Path(tempfile.mkdtemp(prefix=f".build-{target.parent.name}-", dir=home))
        work.chmod(0o755)  # mkdtemp's 0700 would stay on the entry
        kept = home / f"build-{target.parent.name}.log"  # a failed build's log
        say(
            f"building {package} for ROS 2 {distro()} and Python {sys.version.split()[0]} "
            f"(once, about half a minute) in {home}"
        )
        try:
            code = cmake.run(SOURCES / package, work, say)
            if code != 0:
                raise InterfaceBuildError(
                    f"the build of {package} failed (exit code {code}): see {kept}"
                )
            for done in ("build", "src"):  # the objects: 14 MB nobody reads again
                shutil.rmtree(work / done, ignore_errors=True)
            shutil.rmtree(target.parent, ignore_errors=True)  # a remnant without install/
            os.rename(work, target.parent)  # atomic: the entry appears complete
        except BaseException:
            if (work / "build.log").is_file():
                shutil.copy(work / "build.log", kept)
            shutil.rmtree(work, ignore_errors=True)
            raise
    say(f"{package} built: {target}")
    return target


@contextmanager
def _locked(path: Path, say: Progress, package: str):
    with open(path, "w") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            say(f"waiting for another process building {package} (lock {path})")
            fcntl.flock(lock, fcntl.LOCK_EX)
        yield


# --- using a build ------------------------------------------------------------------


def activate(path: Path | str, package: str = PACKAGE) -> dict[str, str]:
    """Make the build at the install prefix ``path`` importable in this
    process (its ``site-packages`` on ``sys.path``, its libraries loaded, see
    the module's docstring) and return what a child process's environment
    needs: ``PYTHONPATH``, ``LD_LIBRARY_PATH`` and ``AMENT_PREFIX_PATH``, each
    with this process's value after the build's folder. ``os.environ`` is left
    as it is. Raises :class:`InterfaceBuildError` when a library cannot be
    loaded (a Python without the wheels' library path, see the message)."""
    path = Path(path)
    site = path / "lib" / PY / "site-packages"
    lib = path / "lib"
    if not (site / package).is_dir():
        raise InterfaceBuildError(f"no {package} for {PY} in {site}")
    if str(site) not in sys.path:
        sys.path.insert(0, str(site))
        importlib.invalidate_caches()
    _preload(sorted(lib.glob(f"lib{package}__*.so")))

    def first(folder: Path, name: str) -> str:
        rest = [p for p in os.environ.get(name, "").split(os.pathsep) if p and p != str(folder)]
        return os.pathsep.join([str(folder), *rest])

    return {
        "PYTHONPATH": first(site, "PYTHONPATH"),
        "LD_LIBRARY_PATH": first(lib, "LD_LIBRARY_PATH"),
        "AMENT_PREFIX_PATH": first(path, "AMENT_PREFIX_PATH"),
    }


def _preload(libraries: list[Path]) -> None:
    """Load the package's libraries, each after those it needs (passes until
    nothing more loads: the order among them is not known here)."""
    pending = list(libraries)
    while pending:
        errors = {}
        for lib in pending:
            try:
                ctypes.CDLL(str(lib), mode=ctypes.RTLD_GLOBAL)
            except OSError as error:
                errors[lib] = error
        if len(errors) == len(pending):
            failed, why = next(iter(errors.items()))
            raise InterfaceBuildError(
                f"cannot load {failed.name}: {why} (run the Python of the venv holding the "
                "ROS wheels: its bootstrapper sets the library path at start)"
            )
        pending = list(errors)


def ensure(progress: Progress | None = None, package: str = PACKAGE) -> dict[str, str]:
    """:func:`locate` or :func:`build`, then :func:`activate`: what the node
    calls before importing the types. Returns the children's environment."""
    return activate(locate(package) or build(progress, package), package)


@functools.cache
def import_interfaces(progress: Progress | None = None) -> SimpleNamespace:
    """The package's types (``Event``, ``Facts``, ``ExecuteTasks``,
    ``PlanTasks``, ``GetState``, ``UpdateFacts``), found, built or taken from
    the cache and activated first (:func:`ensure`). Imports no rclpy itself
    (the generated modules import the type-support loader)."""
    ensure(progress)
    msg = importlib.import_module(f"{PACKAGE}.msg")
    srv = importlib.import_module(f"{PACKAGE}.srv")
    action = importlib.import_module(f"{PACKAGE}.action")
    return SimpleNamespace(
        Event=msg.Event,
        Facts=msg.Facts,
        ExecuteTasks=action.ExecuteTasks,
        PlanTasks=srv.PlanTasks,
        GetState=srv.GetState,
        UpdateFacts=srv.UpdateFacts,
        Skill=action.Skill,
        Check=srv.Check,
    )


def import_type(name: str, progress: Progress | None = None):
    """The ROS type ``name`` (``geometry_msgs/msg/PoseStamped``,
    ``nav2_msgs/action/NavigateToPose``): from an importable package (the
    wheels, a sourced workspace), else from one htn ships, built once
    (:func:`ensure`). An unknown package or type is an
    :class:`InterfaceBuildError` saying so."""
    parts = name.split("/")
    if len(parts) != 3 or parts[1] not in ("msg", "srv", "action") or not all(parts):
        raise InterfaceBuildError(f"'{name}' is not a ROS type name (package/msg|srv|action/Name)")
    package, kind, type_name = parts
    if package in SHIPPED:
        if package == PACKAGE:
            import_interfaces(progress)
        elif workspace_prefix(package) is None:
            ensure(progress, package)
    elif importlib.util.find_spec(package) is None:
        raise InterfaceBuildError(
            f"unknown ROS type {name}: no package {package} is installed "
            "(source its workspace, or install its wheel)"
        )
    module = importlib.import_module(f"{package}.{kind}")
    found = getattr(module, type_name, None)
    if found is None:
        raise InterfaceBuildError(f"unknown ROS type {name}: {package}.{kind} has no {type_name}")
    return found
