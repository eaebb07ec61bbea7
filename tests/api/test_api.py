"""The public API: one use case a function (``htn.plan``, ``htn.run``,
``htn.validate``, ``htn.transform``, ``htn.evaluate``, ``htn.stats``), each
taking paths or loaded objects, raising located errors, never printing or
exiting; ``import htn`` stays light."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import htn
from htn.api.run import prepare, read_run_log
from htn.jshop.language.errors import HtnError
from htn.jshop.readers.load import load_inputs
from htn.robot.symbolic import SymbolicRobot

from conftest import ROOT

DOMAIN = ROOT / "domains" / "domestic.jshop"
BRING = ROOT / "problems" / "bring_object.jshop"
KITCHEN = ROOT / "domains" / "kitchen.jshop"
TRAY = ROOT / "problems" / "tray_three.jshop"


def _modules_after(code: str) -> list[str]:
    r = subprocess.run(
        [sys.executable, "-c", code + "\nimport sys, json\nprint(json.dumps(sorted(sys.modules)))"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.splitlines()[-1])


def test_import_htn_loads_no_use_case_and_no_library():
    loaded = _modules_after("import htn")
    assert [m for m in loaded if m.startswith("htn")] == ["htn"]
    assert not {"click", "rich", "lark", "py_trees"} & set(loaded)


def test_the_command_line_starts_without_the_use_cases():
    loaded = set(_modules_after("import htn.cli.main"))
    assert (
        not {
            "lark",
            "py_trees",
            "click",  # the group is imported for a command that needs it (cli/fast.py)
            "htn.api.plan",
            "htn.api.run",
            "htn.jshop.search.planner",
            "htn.executor.dispatcher",
        }
        & loaded
    )


def test_the_use_cases_are_attributes_of_htn():
    assert htn.plan is __import__("htn.api.plan", fromlist=["plan"]).plan
    assert htn.run.__module__ == "htn.api.run"
    assert {"plan", "run", "validate", "transform_plan", "evaluate", "stats"} <= set(dir(htn))
    # htn.transform is the framework's package, a plain one
    import importlib
    import types

    from htn.transform import framework

    package = importlib.import_module("htn.transform")
    assert type(package) is types.ModuleType and package.framework is framework
    assert not callable(package) and htn.transform is package


def test_the_root_use_case_registry_makes_no_import_circle():
    from package_graph import cycles, imports_of, package_modules

    modules = package_modules()
    graph = {name: imports_of(name, path, modules) for name, path in modules.items()}
    graph["htn"] |= set(htn.USE_CASES.values())  # imported by name, on first use
    assert cycles(graph) == []


# ---------------------------------------------------------------- plan


def test_plan_streams_plans_with_trees_and_statistics():
    plans = htn.plan(DOMAIN, BRING, plans=3)
    assert plans.warnings == [] and plans.stats["plans_found"] == 0  # nothing searched yet
    found = list(plans)
    assert [p.index for p in found] == [0, 1, 2] and all(p.tree for p in found)
    assert plans.stats["plans_found"] == 3 and plans.stats["shortest_plan"] == 8
    assert plans.stats["expansions"] > 0 and not plans.stats["timed_out"]
    cli = subprocess.run(
        [sys.executable, "-m", "htn", "plan", DOMAIN, BRING, "-n", "3", "-f", "json"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    records = [json.loads(line) for line in cli.stdout.splitlines()]
    assert [p.lines() for p in found] == [r["steps"] for r in records[:3]]
    assert [p.tree.to_dict() for p in found] == [r["tree"] for r in records[:3]]
    assert set(plans.stats) == set(records[3]) - {"type", "domain", "problem"}


def test_plan_takes_loaded_objects_and_every_plan():
    dom, prob = load_inputs(str(DOMAIN), str(BRING))
    plans = htn.plan(dom, prob, plans=None, trees=False)
    found = list(plans)
    assert len(found) == 3 and plans.domain is dom and plans.problem is prob
    assert all(p.tree is None for p in found)


def test_plan_stops_at_its_timeout_and_keeps_what_it_found(tmp_path):
    domain, problem = tmp_path / "d.jshop", tmp_path / "p.jshop"
    domain.write_text(
        "(defdomain d ((:operator (!a ?x) () () ()) "
        "(:method (m) ((p ?x) (p ?y) (p ?z)) ((!a ?x) (!a ?y) (!a ?z)))))"
    )
    problem.write_text("(defproblem p d (" + " ".join(f"(p {i})" for i in range(200)) + ") ((m)))")
    plans = htn.plan(domain, problem, plans=None, timeout=0.3, trees=False)
    n = sum(1 for _ in plans)
    assert plans.stats["timed_out"] and n == plans.stats["plans_found"] > 0


def test_plan_explains_why_there_is_no_plan(tmp_path):
    domain, problem = tmp_path / "d.jshop", tmp_path / "p.jshop"
    domain.write_text("(defdomain d ((:operator (!a) ((never)) () ()) (:method (m) () ((!a)))))")
    problem.write_text("(defproblem p d () ((m)))")
    plans = htn.plan(domain, problem)
    assert list(plans) == []
    (why,) = plans.explain()
    assert any("(never)" in line for line in why.lines())


def test_input_errors_are_located_and_nothing_is_printed(tmp_path, capsys):
    domain = tmp_path / "d.jshop"
    domain.write_text("(defdomain d ((:operator (!a) () () ())\n  (:method (m) () ((!b ?x)))))")
    problem = tmp_path / "p.jshop"
    problem.write_text("(defproblem p d () ((n)))")
    with pytest.raises(HtnError) as bad:
        htn.plan(domain, problem)
    assert bad.value.file == str(problem) and bad.value.line == 1
    with pytest.raises(HtnError, match="no such file"):
        htn.plan(tmp_path / "nope.jshop", problem)
    assert capsys.readouterr() == ("", "")


# ---------------------------------------------------------------- run


def test_run_a_plan_object_with_its_own_robot_and_every_event():
    plans = htn.plan(DOMAIN, BRING)
    plan = next(iter(plans))
    instance = plans.problem.instances[0]
    robot = SymbolicRobot(plans.domain, instance, plans.functions, {"effect": 0.3}, seed=3)
    seen = []
    result = htn.run(
        plan,
        robot=robot,
        domain=plans.domain,
        problem=plans.problem,
        replan=True,
        on_event=seen.append,
    )
    assert result.ok and result.summary.retries > 0
    assert seen == result.events
    assert seen[0]["event"] == "header" and seen[0]["plan"] is None
    assert seen[-1]["event"] == "summary" and seen[-1]["result"] == "verified"
    assert {"fault", "retrying", "verified"} <= {e["event"] for e in seen}
    assert result.notes == []  # the plan object had its tree
    assert robot.sim_time == result.summary.sim_time


def test_run_by_name_with_faults_replan_and_a_log_that_replays(tmp_path):
    plan = tmp_path / "plan.txt"
    r = subprocess.run(
        [sys.executable, "-m", "htn", "plan", DOMAIN, BRING, "-o", plan],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert r.returncode == 0, r.stderr
    log = tmp_path / "run.jsonl"
    first = htn.run(
        plan,
        robot="symbolic",
        faults="effect=0.4",
        seed=5,
        replan=True,
        retries={"find_person": 0},
        log=log,
    )
    header = json.loads(log.read_text().splitlines()[0])
    assert header["retries"]["!find_person"] == 0 and header["argv"] is None
    again = htn.run(**read_run_log(log).options())
    strip = lambda evs: [{k: v for k, v in e.items() if k != "t"} for e in evs[1:]]  # noqa: E731
    assert strip(again.events) == strip(first.events)
    assert again.summary == first.summary


def test_run_refuses_bad_input_with_its_location(tmp_path, capsys):
    plan = tmp_path / "plan.txt"
    plan.write_text(
        f"; domain: {DOMAIN}\n; problem: {BRING}\nPlan cost: 1.0\n\n"
        "(!fly jenny)\n--------------------\n"
    )
    with pytest.raises(HtnError) as bad:
        htn.run(plan, robot="symbolic")
    assert (bad.value.file, bad.value.line) == (str(plan), 5)
    plan.write_text(plan.read_text().replace("(!fly jenny)", "(!say jenny task_accepted)"))
    with pytest.raises(HtnError, match="unknown robot 'wheelbarrow'"):
        htn.run(plan, robot="wheelbarrow")
    with pytest.raises(HtnError, match="--log: no such folder"):
        htn.run(plan, robot="symbolic", log=tmp_path / "no" / "run.jsonl")
    assert htn.run(plan, robot="symbolic").ok
    with pytest.raises(HtnError, match="a plan object runs with a domain and a problem"):
        htn.run(next(iter(htn.plan(DOMAIN, BRING))), robot="symbolic")
    assert capsys.readouterr() == ("", "")


def test_a_prepared_run_halted_before_it_starts_ends_interrupted(tmp_path):
    plans = htn.plan(DOMAIN, BRING)
    with prepare(
        next(iter(plans)), robot="symbolic", domain=plans.domain, problem=plans.problem
    ) as execution:
        execution.halt("a program said stop")
        result = execution.execute()
    assert result.result == "interrupted" and result.summary.verified == 0
    assert result.events[-2]["detail"].startswith("a program said stop")


# ---------------------------------------------------------------- validate, transform, stats, evaluate


def test_validate_gives_a_verdict_per_plan():
    plans = list(htn.plan(DOMAIN, BRING, plans=None))
    verdicts = htn.validate(DOMAIN, BRING, plans)
    assert [v.valid for v in verdicts] == [True, True, True]
    broken = plans[0]
    broken.steps, broken.cost = broken.steps[2:4], 2.0  # detect before going there
    (v,) = htn.validate(DOMAIN, BRING, broken)
    assert not v.valid and v.failed_step == 1 and "does not hold" in v.verdict.reason


@pytest.mark.slow
def test_transform_is_callable_and_gives_a_checked_plan(tmp_path):
    done = htn.transform_plan(KITCHEN, TRAY, rules="tray")
    assert done.document["applied"] == ["tray"]
    assert done.plan.tree is not None and done.tasks
    out = tmp_path / "t.txt"
    out.write_text(done.plan_file_text(str(out)))
    assert all(v.valid for v in htn.validate(KITCHEN, TRAY, out))
    with pytest.raises(HtnError, match="unknown rule"):
        htn.transform_plan(KITCHEN, TRAY, rules=["teleport"])
    # the registered framework is left as it was
    assert len(htn.transform_plan(KITCHEN, TRAY).document["log"]) >= len(done.document["log"])


def test_stats_of_the_papers_scenarios():
    rows = htn.stats(repeat=1)
    assert [(r.plans, r.distinct_plans, r.min_length) for r in rows] == [(3, 1, 8), (1, 1, 5)]


def test_evaluate_compares_the_plans_in_this_process():
    pytest.importorskip("scipy")
    from htn.api.evaluate import Progress

    started, batches = [], []

    class Seen(Progress):  # one progress object; what it leaves out does nothing
        def started(self, workers, notes):
            started.append(workers)

        def batch(self, records, runs):
            batches.append(runs)

    result = htn.evaluate(TRAY, runs=4, progress=Seen())
    assert started == [1] and sum(batches) == 4
    doc = result.document()
    assert doc["runs"] == 4 and doc["applied"] and set(doc["metrics"]) >= {"navigation"}
