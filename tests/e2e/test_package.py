"""The installed package, as a new user gets it: a wheel in a fresh virtualenv.

Each virtualenv is real (``python -m venv``) and gets the wheel built from
this checkout plus its dependencies from the package index; the commands run
from a folder outside the checkout.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from conftest import ROOT

BASIC_PLAN = "Plan cost: 2.0\n\n(!drop kiwi)\n(!pickup banjo)\n--------------------\n"
BASIC_DOMAIN = """(defdomain basic (
  (:operator (!pickup ?a) () () ((have ?a)))
  (:operator (!drop ?a) ((have ?a)) ((have ?a)) ())
  (:method (swap ?x ?y)
    ((have ?x) (not (have ?y))) ((!drop ?x) (!pickup ?y))
    ((have ?y) (not (have ?x))) ((!drop ?y) (!pickup ?x)))))
"""
BASIC_PROBLEM = "(defproblem problem basic ((have kiwi)) ((swap banjo kiwi)))\n"


# one xdist worker builds the wheel (in the checkout's build/) for all of them
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("wheel")]


def sh(*args, cwd, env=None, timeout=600):
    return subprocess.run(
        [str(a) for a in args], cwd=cwd, capture_output=True, text=True, timeout=timeout, env=env
    )


class Venv:
    def __init__(self, path: Path):
        self.path = path
        self.bin = path / "bin"

    def pip(self, *args):
        r = sh(self.bin / "python", "-m", "pip", "install", "-q", *args, cwd=self.path)
        assert r.returncode == 0, r.stdout + r.stderr
        return r

    def run(self, *args, cwd):
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
        env["PATH"] = f"{self.bin}{os.pathsep}{env.get('PATH', '')}"
        return sh(*args, cwd=cwd, env=env)


def make_venv(path: Path) -> Venv:
    r = sh(sys.executable, "-m", "venv", path, cwd=path.parent)
    assert r.returncode == 0, r.stderr
    return Venv(path)


@pytest.fixture(scope="session")
def wheel(checkout_wheel) -> Path:
    return checkout_wheel


@pytest.fixture(scope="session")
def core(tmp_path_factory, wheel) -> Venv:
    """The core install: htn with lark, click and rich only."""
    venv = make_venv(tmp_path_factory.mktemp("core") / "venv")
    venv.pip(wheel)
    return venv


@pytest.fixture
def elsewhere(tmp_path) -> Path:
    """A working folder outside the checkout."""
    folder = tmp_path / "work"
    folder.mkdir()
    assert ROOT not in folder.parents
    return folder


# the package data a command reads at run time, as the checkout holds it
DATA = [
    "jshop/readers/*.lark",
    "domains/*.jshop",
    "domains/*.toml",
    "problems/*.jshop",
    "transform/*.jshop",
    "view/static/*",
    "ros/interfaces/*/package.xml",
    "ros/interfaces/*/CMakeLists.txt",
    "ros/interfaces/*/*/*.msg",
    "ros/interfaces/*/*/*.srv",
    "ros/interfaces/*/*/*.action",
]


def test_the_wheel_holds_the_package_data_and_nothing_of_the_tests_or_benchmarks(wheel):
    import zipfile

    names = set(zipfile.ZipFile(wheel).namelist())
    data = sorted(
        f"htn/{p.relative_to(ROOT).as_posix()}"
        for pattern in DATA
        for p in ROOT.glob(pattern)
        if p.is_file()
    )
    assert len(data) >= 30 and [d for d in data if d not in names] == []
    extra = [n for n in names if n.startswith("htn/") and not n.endswith(".py") and n not in data]
    assert extra == []
    outside = ("tests/", "benchmarks/", "docs/", "examples/", ".ci/", "build/")
    assert [
        n
        for n in names
        if n.startswith(outside) or n.startswith(tuple(f"htn/{o}" for o in outside))
    ] == []
    assert sorted({n.split("/")[0] for n in names}) == ["htn", f"htn-{_version(wheel)}.dist-info"]


def _version(wheel: Path) -> str:
    return wheel.name.split("-")[1]


def test_the_wheel_installs_one_import_package(core):
    r = core.run(
        core.bin / "python",
        "-c",
        textwrap.dedent("""
        import json
        from importlib.metadata import distribution
        files = distribution("htn").files
        print(json.dumps(sorted({f.parts[0] for f in files if f.suffix == ".py"})))
        """),
        cwd=core.path,
    )
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout) == ["htn"]


def test_the_core_install_plans_runs_and_names_missing_extras(core, elsewhere):
    assert core.run("htn", "stats", "--repeat", "1", cwd=elsewhere).returncode == 0
    r = core.run("htn", "examples", ".", cwd=elsewhere)
    assert r.returncode == 0, r.stderr
    assert (elsewhere / "domains" / "domestic.toml").is_file()
    r = core.run(
        "htn",
        "plan",
        "domains/domestic.jshop",
        "problems/bring_object.jshop",
        "-o",
        "plan.txt",
        cwd=elsewhere,
    )
    assert r.returncode == 0, r.stderr
    r = core.run("htn", "run", "plan.txt", "--robot", "symbolic", cwd=elsewhere)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.splitlines()[-1].startswith("verified: 8 of 8 steps verified")
    r = core.run(
        "htn",
        "validate",
        "domains/domestic.jshop",
        "problems/bring_object.jshop",
        "plan.txt",
        cwd=elsewhere,
    )
    assert r.returncode == 0, r.stderr
    r = core.run(
        "htn", "transform", "domains/kitchen.jshop", "problems/tray_three.jshop", cwd=elsewhere
    )
    assert r.returncode == 0, r.stderr
    r = core.run("htn", "run", "plan.txt", "--sim", cwd=elsewhere)
    assert r.returncode == 2
    assert r.stderr == "htn run --sim needs the sim extra: pip install 'htn[sim]'\n"
    r = core.run("htn", "evaluate", "problems/tray_three.jshop", cwd=elsewhere)
    assert r.returncode == 2
    assert r.stderr == "htn evaluate needs the eval extra: pip install 'htn[eval]'\n"
    r = core.run("htn", "ros", "--help", cwd=elsewhere)
    assert r.returncode == 0 and "Needs the ros extra: pip install 'htn[ros]'" in r.stdout
    r = core.run("htn", "ros", "node", "domains/domestic.jshop", cwd=elsewhere)
    assert r.returncode == 2 and r.stderr.startswith("htn ros needs the ros extra")
    r = core.run("htn", "run", "plan.txt", "--robot", "ros", cwd=elsewhere)
    assert r.returncode == 2
    assert r.stderr == "--robot ros needs the ros extra: pip install 'htn[ros]'\n"
    r = core.run(core.bin / "python", "-m", "htn", "--version", cwd=elsewhere)
    assert r.returncode == 0 and r.stdout.startswith("htn, version")


PLUGIN_PYPROJECT = """
[build-system]
requires = ["setuptools>=61"]
build-backend = "setuptools.build_meta"

[project]
name = "htn-toy-plugin"
version = "0.1"

[project.entry-points."htn.actions"]
toy = "toyplug.actions"

[project.entry-points."htn.robots"]
toy = "toyplug.robot:make_robot"

[project.entry-points."htn.transformations"]
toy = "toyplug.rules:register"
"""

PLUGIN_RULES = '''
"""A transformation rule that applies wherever a transport exists and
changes nothing (the framework then leaves the plan as it is)."""


def keep(workspace, schemas):
    return None


def register(framework):
    framework.register_transformation(keep, "(transport ?t ?o ?f ?d ?k)", "toy-keep")
'''

PLUGIN_ACTIONS = '''
"""Action state machines for the basic domain's operators on the toy robot."""
from htn.executor.machines import ActionMachine, action


@action("!pickup", domain="basic")
class Pickup(ActionMachine):
    # skills and checks by name, as the bundled machines call them
    def execute(self, robot, thing):
        return robot.act("pick_up", thing)

    def monitor(self, robot, thing):
        return robot.check("have", thing, True)

    def holds(self, robot, thing):     # checked on every tick while it runs
        return [("toy hand works", lambda: robot.check("hand_ok"))]


@action("!drop", domain="basic")
class Drop(ActionMachine):
    # or the robot's own methods, called directly
    def execute(self, robot, thing):
        return robot.drop(thing)

    def monitor(self, robot, thing):
        return robot.check_have(thing, False)
'''

PLUGIN_ROBOT = '''
"""A toy robot with one hand that remembers what it has."""
from htn.robot.interface import Check, Robot, SkillResult, check, skill


class ToyRobot(Robot):
    def __init__(self, have):
        self.have = set(have)

    @skill("pick_up")
    def pick_up(self, thing):
        self.sim_time += 0.5
        self.have.add(thing)
        return SkillResult(True, f"toy hand took {thing}")

    def drop(self, thing):
        self.sim_time += 0.5
        self.have.discard(thing)
        return SkillResult(True, f"toy hand let go of {thing}")

    def check_have(self, thing, expected):       # the check "have", by its method name
        return Check((thing in self.have) == expected, f"toy sees {sorted(self.have)}")

    @check("hand_ok")
    def hand_is_fine(self):
        return Check(True, "fine")

    def observe(self):
        return [("have", (t,)) for t in sorted(self.have)]


def make_robot(request):
    request.fault_rates(())          # the toy robot injects no faults
    return ToyRobot(a.args[0] for a in request.instance.state if a.pred == "have")
'''


def test_a_plugin_adds_an_action_machine_and_a_robot(core, tmp_path, elsewhere):
    plugin = tmp_path / "toy-plugin"
    (plugin / "toyplug").mkdir(parents=True)
    (plugin / "pyproject.toml").write_text(PLUGIN_PYPROJECT)
    (plugin / "toyplug" / "__init__.py").write_text("")
    (plugin / "toyplug" / "actions.py").write_text(PLUGIN_ACTIONS)
    (plugin / "toyplug" / "robot.py").write_text(PLUGIN_ROBOT)
    (plugin / "toyplug" / "rules.py").write_text(PLUGIN_RULES)
    core.pip(plugin)
    (elsewhere / "basic").write_text(BASIC_DOMAIN)
    (elsewhere / "problem").write_text(BASIC_PROBLEM)
    (elsewhere / "plan.txt").write_text(BASIC_PLAN)
    r = core.run(
        "htn",
        "run",
        "plan.txt",
        "--domain",
        "basic",
        "--problem",
        "problem",
        "--robot",
        "toy",
        "--log",
        "run.jsonl",
        cwd=elsewhere,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.splitlines()[-1] == (
        "verified: 2 of 2 steps verified, 0 retries, 0 replans, 1.0 s simulated"
    )
    events = [json.loads(line) for line in (elsewhere / "run.jsonl").read_text().splitlines()]
    assert events[0]["event"] == "header" and events[0]["robot"] == "toy"
    details = [e["detail"] for e in events if e["event"] == "feedback"]
    assert details == ["toy hand let go of kiwi", "toy hand took banjo"]
    r = core.run(
        "htn",
        "run",
        "plan.txt",
        "--domain",
        "basic",
        "--problem",
        "problem",
        "--robot",
        "toy",
        "--faults",
        "effect=0.5",
        cwd=elsewhere,
    )
    assert r.returncode == 2 and "unknown fault 'effect'" in r.stderr
    # the transformation rule registered through htn.transformations
    assert core.run("htn", "examples", ".", cwd=elsewhere).returncode == 0
    r = core.run(
        "htn",
        "transform",
        "domains/kitchen.jshop",
        "problems/tray_three.jshop",
        "--rules",
        "toy-keep",
        cwd=elsewhere,
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("no transformation applies")
    r = core.run(
        "htn",
        "transform",
        "domains/kitchen.jshop",
        "problems/tray_three.jshop",
        "--rules",
        "toy-nothing",
        cwd=elsewhere,
    )
    assert r.returncode == 2 and "toy-keep" in r.stderr  # the known rules include it


def test_robot_framework_and_htn_side_by_side(tmp_path_factory, wheel, elsewhere):
    venv = make_venv(tmp_path_factory.mktemp("sim") / "venv")
    venv.pip(f"{wheel}[sim]", "robotframework")
    r = venv.run("robot", "--version", cwd=elsewhere)
    assert "Robot Framework" in r.stdout + r.stderr
    assert venv.run("htn", "examples", ".", cwd=elsewhere).returncode == 0
    r = venv.run(
        "htn",
        "plan",
        "domains/domestic.jshop",
        "problems/guide_robot.jshop",
        "-o",
        "plan.txt",
        cwd=elsewhere,
    )
    assert r.returncode == 0, r.stderr
    r = venv.run("htn", "run", "plan.txt", "--sim", "-q", cwd=elsewhere)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.startswith("verified: 5 of 5 steps verified")
