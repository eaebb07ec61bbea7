"""htn_interfaces, the ROS 2 types of htn's node: found, or built once with
CMake into the per-user cache (:mod:`htn.ros.interfaces`), and usable across
processes. The build's bookkeeping (checks, the wheels' CMake fix, the cache,
the lock) is tested everywhere with a stand-in for CMake; the real build and
a two-process exchange need the ``ros`` extra and are skipped without it."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
import tomllib
import uuid
from importlib.util import find_spec
from pathlib import Path

import pytest

from htn.ros import cmake, interfaces
from htn.ros.interfaces import InterfaceBuildError

from conftest import ROOT

# the tests that need ROS carry the "ros" marker once pyproject registers it
# (--strict-markers makes an unregistered one a collection error for the whole run)
_MARKERS = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
needs_ros = (
    pytest.mark.ros if any(m.startswith("ros:") for m in _MARKERS["markers"]) else pytest.mark.slow
)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache of its own, for ROS 2 Jazzy, with the build's checks passed."""
    monkeypatch.setenv("HTN_ROS_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("ROS_DISTRO", "jazzy")
    monkeypatch.setattr(interfaces, "check", lambda package=interfaces.PACKAGE: None)
    monkeypatch.setattr(cmake, "fix_exports", lambda prefix=None: [])
    return tmp_path / "cache"


def fake_cmake(code=0, entered=None, go_on=None):
    """A stand-in for :func:`cmake.run`: makes an install (exit code 0) or
    fails with ``code``; counts its calls; may wait for ``go_on``."""
    calls = []

    def run(source, work, say):
        calls.append(work)
        if entered:
            entered.set()
        if go_on:
            assert go_on.wait(30)
        (work / "build.log").write_text("the compiler's words\n")
        if code == 0:
            (work / "install" / "lib").mkdir(parents=True)
            (work / "build").mkdir()
        return code

    run.calls = calls
    return run


# --- where the build goes, and what a build lacks ----------------------------------


def test_the_cache_is_per_user_per_ros_and_python_and_per_source(monkeypatch, tmp_path):
    monkeypatch.delenv("HTN_ROS_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setenv("ROS_DISTRO", "kilted")
    py = f"py{sys.version_info.major}{sys.version_info.minor}"
    assert interfaces.cache_dir() == tmp_path / "htn" / "ros" / f"kilted-{py}"
    assert re.fullmatch(r"[0-9a-f]{16}", interfaces.source_hash())
    assert (
        interfaces.cached_install()
        == interfaces.cache_dir() / f"htn_interfaces-{interfaces.source_hash()}" / "install"
    )
    nav2 = interfaces.cached_install("nav2_msgs")
    assert (
        nav2
        == interfaces.cache_dir() / f"nav2_msgs-{interfaces.source_hash('nav2_msgs')}" / "install"
    )
    assert interfaces.source_hash("nav2_msgs") != interfaces.source_hash()
    monkeypatch.setenv("HTN_ROS_CACHE", str(tmp_path / "ci"))
    assert interfaces.cache_dir() == tmp_path / "ci" / f"kilted-{py}"


def test_the_source_is_a_ros_interface_package():
    source = interfaces.SOURCE
    xml = (source / "package.xml").read_text()
    assert '<package format="3">' in xml and "<name>htn_interfaces</name>" in xml
    assert "<member_of_group>rosidl_interface_packages</member_of_group>" in xml
    lists = (source / "CMakeLists.txt").read_text()
    files = sorted(p.relative_to(source).as_posix() for p in source.glob("*/*.*"))
    assert files == [
        "action/ExecuteTasks.action",
        "action/Skill.action",
        "msg/Event.msg",
        "msg/Facts.msg",
        "srv/Check.srv",
        "srv/GetState.srv",
        "srv/PlanTasks.srv",
        "srv/UpdateFacts.srv",
    ]
    assert all(f'"{f}"' in lists for f in files)
    for path in source.glob("*/*.*"):  # every field has its comment
        lines = path.read_text().splitlines()
        for i, line in enumerate(lines):
            if line and not line.startswith(("#", "---")):
                assert lines[i - 1].startswith("#"), f"{path.name}: {line} has no comment"


def test_nav2_msgs_is_jazzys_navigate_to_pose_alone():
    source = interfaces.SOURCES / "nav2_msgs"
    assert "<name>nav2_msgs</name>" in (source / "package.xml").read_text()
    assert '"action/NavigateToPose.action"' in (source / "CMakeLists.txt").read_text()
    fields = [
        ln.split()[:2]
        for ln in (source / "action" / "NavigateToPose.action").read_text().splitlines()
        if ln and not ln.startswith("#") and "=" not in ln
    ]
    assert fields == [
        ["geometry_msgs/PoseStamped", "pose"],
        ["string", "behavior_tree"],
        ["---"],
        ["uint16", "error_code"],
        ["string", "error_msg"],
        ["---"],
        ["geometry_msgs/PoseStamped", "current_pose"],
        ["builtin_interfaces/Duration", "navigation_time"],
        ["builtin_interfaces/Duration", "estimated_time_remaining"],
        ["int16", "number_of_recoveries"],
        ["float32", "distance_remaining"],
    ]


def test_a_missing_compiler_cmake_or_make_is_named_in_one_line(monkeypatch):
    monkeypatch.setenv("ROS_DISTRO", "jazzy")
    with pytest.raises(InterfaceBuildError) as caught:
        interfaces.check(which=lambda name: None)
    message = str(caught.value)
    assert "\n" not in message
    for what in ("a C compiler (cc or gcc)", "a C++ compiler (c++ or g++)", "cmake", "make"):
        assert what in message and what in caught.value.missing
    assert "apt install build-essential cmake" in message


def test_missing_python_headers_are_named(monkeypatch, tmp_path):
    real = cmake.sysconfig.get_paths
    monkeypatch.setattr(
        cmake.sysconfig, "get_paths", lambda *a, **k: {**real(*a, **k), "include": str(tmp_path)}
    )
    with pytest.raises(InterfaceBuildError, match=rf"Python.h not in {re.escape(str(tmp_path))}"):
        cmake.check("jazzy", "htn_interfaces", which=lambda name: "/usr/bin/" + name)


def test_without_ros_the_message_says_which_extra_to_install(monkeypatch, tmp_path):
    monkeypatch.setattr(cmake.sysconfig, "get_path", lambda name: str(tmp_path))
    with pytest.raises(InterfaceBuildError) as caught:
        cmake.check("", "htn_interfaces", which=lambda name: "/usr/bin/" + name)
    assert "ROS 2" in str(caught.value) and "pip install 'htn[ros]'" in str(caught.value)
    assert "ament_cmake" in str(caught.value) and "rosidl_default_generators" in str(caught.value)


def test_the_wheels_cmake_exports_get_this_machines_include_folders_once(tmp_path):
    folder = tmp_path / "share" / "x_msgs" / "cmake"
    folder.mkdir(parents=True)
    path = folder / "export_x_msgs__rosidl_generator_pyExport.cmake"
    here = str(tmp_path)
    path.write_text(
        "set_target_properties(x PROPERTIES\n  INTERFACE_INCLUDE_DIRECTORIES "
        f'"/opt/python/cp311-cp311/include/python3.11;{here};'
        '/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include"\n)\n'
    )
    assert cmake.fix_exports(tmp_path) == [path]
    folders = re.search(r'DIRECTORIES "([^"]*)"', path.read_text()).group(1).split(";")
    assert folders[0] == cmake.sysconfig.get_paths()["include"]
    assert folders[1] == here  # a folder that exists stays
    assert "/opt/python" not in path.read_text() or find_spec("numpy") is None
    assert cmake.fix_exports(tmp_path) == []  # idempotent
    assert not list(folder.glob("*.htn-*"))


# --- the cache: built once, never half, one builder at a time ----------------------


def test_a_build_is_published_whole_and_then_reused(cache, monkeypatch):
    run = fake_cmake()
    monkeypatch.setattr(cmake, "run", run)
    said = []
    path = interfaces.build(progress=said.append)
    assert path == interfaces.cached_install() and path.is_dir()
    assert not (path.parent / "build").exists()  # the objects are not kept
    assert interfaces.build() == path and len(run.calls) == 1
    assert any("once" in s for s in said) and said[-1].endswith(str(path))
    assert not list(path.parent.parent.glob(".build-*"))


def test_a_failed_build_leaves_its_log_and_nothing_usable(cache, monkeypatch):
    monkeypatch.setattr(cmake, "run", fake_cmake(code=2))
    with pytest.raises(InterfaceBuildError, match="exit code 2") as caught:
        interfaces.build()
    log = Path(re.search(r"see (\S+)$", str(caught.value)).group(1))
    assert log.read_text() == "the compiler's words\n"
    assert not interfaces.cached_install().exists()
    assert not list(interfaces.cache_dir().glob(".build-*"))


def test_a_second_process_waits_for_the_first_build_and_uses_it(cache, monkeypatch):
    entered, go_on = threading.Event(), threading.Event()
    run = fake_cmake(entered=entered, go_on=go_on)
    monkeypatch.setattr(cmake, "run", run)
    results, waiting = [], threading.Event()

    def second_says(message):
        if message.startswith("waiting for another process"):
            waiting.set()

    first = threading.Thread(target=lambda: results.append(interfaces.build()))
    first.start()
    assert entered.wait(30)
    second = threading.Thread(target=lambda: results.append(interfaces.build(second_says)))
    second.start()
    assert waiting.wait(30)  # the lock holds the second builder
    go_on.set()
    first.join(30)
    second.join(30)
    assert len(run.calls) == 1 and results == [interfaces.cached_install()] * 2


# --- the real thing: a build, and two processes talking ----------------------------


def ros_environment() -> dict[str, str]:
    """This worker's own ROS domain (0-101: Fast DDS derives its ports from
    it) and discovery on this host only."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    domain = int(re.sub(r"\D", "", worker) or 0) % 102
    return {"ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}


@pytest.fixture(scope="module")
def built():
    """The install prefix of htn_interfaces, built (about 25 s, once per
    user) or found in the cache; skipped without the ros extra, or with the
    reason when this machine lacks a compiler, cmake or the Python headers."""
    if find_spec("rclpy") is None:
        pytest.skip("the ros extra is not installed (pip install -e '.[ros]'): no rclpy")
    try:
        return interfaces.locate() or interfaces.build(
            progress=lambda message: print(message, file=sys.stderr)
        )
    except InterfaceBuildError as error:
        if error.missing:
            pytest.skip(str(error))
        raise


@needs_ros
def test_a_sourced_workspaces_build_is_used_and_nothing_is_built(built, tmp_path):
    """What a team's ``setup.bash`` sets (its prefix on PYTHONPATH and the
    library path) is enough: :func:`locate` names that prefix, the types
    import, and the (empty) cache stays empty."""
    workspace = tmp_path / "ws" / "install"
    shutil.copytree(built, workspace)
    site = workspace / "lib" / interfaces.PY / "site-packages"
    env = {
        **os.environ,
        "HTN_ROS_CACHE": str(tmp_path / "cache"),
        "PYTHONPATH": str(site),
        "AMENT_PREFIX_PATH": str(workspace),
        "LD_LIBRARY_PATH": os.pathsep.join(
            [str(workspace / "lib"), os.environ.get("LD_LIBRARY_PATH", "")]
        ),
    }
    code = (
        "from htn.ros import interfaces\n"
        "print(interfaces.locate())\n"
        "t = interfaces.import_interfaces()\n"
        "print(t.Facts(add=['(at robby kitchen)']).add)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == [str(workspace), "['(at robby kitchen)']"]
    assert not (tmp_path / "cache").exists()


HERE = Path(__file__).resolve().parent  # exchange_server.py, exchange_client.py


@needs_ros
@pytest.mark.slow
def test_a_goal_its_feedback_its_result_and_the_services_cross_two_processes(built, tmp_path):
    """The server finds the build through the environment a child gets
    (activate's PYTHONPATH, LD_LIBRARY_PATH, AMENT_PREFIX_PATH); the client
    through ``import_interfaces`` in its own process (the library preload)."""
    name = f"htn_test_{uuid.uuid4().hex[:8]}"  # no cross-talk with other runs
    ros = ros_environment()
    began = time.monotonic()
    server = subprocess.Popen(
        [sys.executable, str(HERE / "exchange_server.py"), name],
        env={**os.environ, **interfaces.activate(built), **ros},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        client = subprocess.run(
            [sys.executable, str(HERE / "exchange_client.py"), name],
            env={**os.environ, **ros},
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
        )
    finally:
        server.send_signal(signal.SIGINT)
        _, server_err = server.communicate(timeout=30)
    took = time.monotonic() - began
    assert client.returncode == 0, client.stderr
    assert server.returncode == 0 and "Traceback" not in server_err, server_err
    out = json.loads(client.stdout.splitlines()[-1])
    done = out["done"]
    assert (done["outcome"], done["steps"], done["verified"]) == ("verified", 2, 2)
    assert done["plan"] == ["(!walk robby kitchen sofa)", "(!give robby jenny pringles)"]
    assert done["tree"]["task"] == "((bring jenny pringles))"
    # feedback sent just before the result may be dropped by the client (ros2.md)
    seen = [(e["step"], e["event"]) for e in done["events"]]
    assert seen == [(0, "started"), (0, "succeeded"), (1, "started"), (1, "succeeded")][: len(seen)]
    cancelled = out["cancelled"]
    assert cancelled["outcome"] == "preempted" and len(cancelled["events"]) >= 3
    assert [e["step"] for e in cancelled["events"]][:3] == [0, 1, 2]
    assert cancelled["steps"] >= 3
    refused = out["refused"]
    assert refused["outcome"] == "refused" and refused["error"].startswith("<goal>:1:1: ")
    assert out["before"] == ["(at jenny sofa)", "(at robby kitchen)"]
    assert out["update"] == [True, "", 3]
    assert out["after"] == ["(at jenny kitchen)"] and out["all"] == 3
    print(f"two-process exchange: {took:.1f} s", file=sys.stderr)
