"""htn as a unified-planning engine: registration, solving, statuses, options."""

from __future__ import annotations

import io
import os
import subprocess
import sys
import time

import pytest

pytest.importorskip("unified_planning")

from test_up_cases import REFUSED, SUPPORTED, cases  # noqa: E402
from unified_planning.engines import PlanGenerationResultStatus as Status  # noqa: E402
from unified_planning.engines.plan_validator import SequentialPlanValidator  # noqa: E402
from unified_planning.exceptions import UPUsageError  # noqa: E402
from unified_planning.model.htn import HierarchicalProblem, Method  # noqa: E402
from unified_planning.plans import HierarchicalPlan, PlanKind, SequentialPlan  # noqa: E402
from unified_planning.shortcuts import (  # noqa: E402
    BoolType,
    Fluent,
    InstantaneousAction,
    Not,
    OneshotPlanner,
    PlanValidator,
    get_all_applicable_engines,
    get_environment,
)

import htn.up  # noqa: E402,F401  (registers the engine)

from conftest import ROOT  # noqa: E402

get_environment().credits_stream = None


def solve(problem, timeout=10, **params):
    with OneshotPlanner(name="htn", params=params) as planner:
        return planner.solve(problem, timeout=timeout)


def up_valid(problem, plan) -> bool:
    """UP's own validator on the plan's actions (it refuses hierarchical kinds
    by its check only: the actions are a flat plan)."""
    v = SequentialPlanValidator()
    v.skip_checks = True
    return v.validate(problem, plan.action_plan).status.name == "VALID"


def htn_valid(problem, plan):
    with PlanValidator(name="htn") as v:
        return v.validate(problem, plan)


# ---------------------------------------------------------------- registration


def test_import_htn_and_the_command_line_do_not_load_unified_planning():
    code = "import htn, sys; print('unified_planning' in sys.modules, 'htn.up' in sys.modules)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert r.stdout.split() == ["False", "False"], r.stderr
    r = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "htn", "--help"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert r.returncode == 0 and "Usage" in r.stdout
    assert "unified_planning" not in r.stderr


def test_importing_htn_up_registers_the_engine_once():
    factory = get_environment().factory
    assert "htn" in factory.engines
    htn.up.register()
    assert factory.preference_list.count("htn") == 1
    with OneshotPlanner(name="htn") as planner:
        assert type(planner).__name__ == "HtnEngine" and planner.name == "htn"
    with PlanValidator(name="htn") as v:
        assert v.supports_plan(PlanKind.HIERARCHICAL_PLAN)
        assert not v.supports_plan(PlanKind.SEQUENTIAL_PLAN)


def test_an_up_ini_file_registers_the_engine_without_an_import(tmp_path):
    (tmp_path / "up.ini").write_text(
        "[engine htn]\nmodule_name: htn.up.engine\nclass_name: HtnEngine\n"
    )
    code = (
        "from unified_planning.shortcuts import OneshotPlanner, get_environment\n"
        "get_environment().credits_stream = None\n"
        "print(get_environment().factory.preference_list.count('htn'), "
        "OneshotPlanner(name='htn').name)\n"
    )
    env = {**os.environ, "HOME": str(tmp_path)}
    r = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, env=env
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["1", "htn"]


# ---------------------------------------------------------------- UP's test cases


@pytest.mark.parametrize("search", ["dfs", "gbfs", "wastar", "auto"])
@pytest.mark.parametrize("name", SUPPORTED)
def test_every_supported_test_case_gets_a_valid_hierarchical_plan(
    name, search, tmp_path, monkeypatch
):
    """In every search of ``params={"search": ...}`` (``htn plan --search``)."""
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # aries-val's log file, not /tmp's
    problem = cases()[name].problem
    result = solve(problem, search=search)
    assert result.status == Status.SOLVED_SATISFICING, result.log_messages
    plan = result.plan
    assert isinstance(plan, HierarchicalPlan)
    assert set(plan.decomposition.subtasks) == {s.identifier for s in problem.task_network.subtasks}
    assert up_valid(problem, plan)
    assert htn_valid(problem, plan).status.name == "VALID"
    with PlanValidator(name="aries-val") as aries:
        if aries.supports(problem.kind):
            assert aries.validate(problem, plan).status.name == "VALID"
    assert float(result.metrics["engine_internal_time"]) > 0


@pytest.mark.parametrize("name", SUPPORTED)
def test_the_test_cases_own_valid_plans_are_valid_for_htn(name):
    for plan in cases()[name].valid_plans:
        assert htn_valid(cases()[name].problem, plan).status.name == "VALID"


@pytest.mark.parametrize("name", [n for n in SUPPORTED if cases()[n].optimum is not None])
def test_optimize_finds_the_test_cases_optimum_and_says_so(name):
    problem = cases()[name].problem
    result = solve(problem, optimize=True)
    assert result.status == Status.SOLVED_OPTIMALLY
    (cost,) = htn_valid(problem, result.plan).metric_evaluations.values()
    assert cost == cases()[name].optimum


@pytest.mark.parametrize("name", REFUSED)
def test_unsupported_kinds_are_refused_with_ups_error(name):
    problem = cases()[name].problem
    # chosen by kind, UP's factory never picks htn for it
    assert "htn" not in get_all_applicable_engines(problem.kind)
    with OneshotPlanner(name="htn") as planner:
        assert not planner.supports(problem.kind)
        # chosen by name, UP only warns; htn then refuses the problem itself
        with pytest.warns(UserWarning, match="cannot establish whether htn can solve"):
            result = planner.solve(problem)
        assert result.status == Status.UNSUPPORTED_PROBLEM and result.plan is None
        assert "DurativeAction" in result.log_messages[-1].message
        planner.error_on_failed_checks = True
        with pytest.raises(UPUsageError, match="cannot establish whether htn can solve"):
            planner.solve(problem)


def test_a_partial_order_is_refused_until_the_planner_has_one():
    problem = cases()["test:htn-go"].problem.clone()
    problem.task_network.constraints.clear()  # the two subtasks are then unordered
    assert "TASK_ORDER_PARTIAL" in problem.kind.features
    with OneshotPlanner(name="htn") as planner:
        planner.skip_checks = True
        result = planner.solve(problem)
    assert result.status == Status.UNSUPPORTED_PROBLEM
    assert "partially" in result.log_messages[-1].message


def test_classical_problems_are_refused():
    problem = cases()["test:basic"].problem
    with OneshotPlanner(name="htn") as planner:
        assert not planner.supports(problem.kind)
        planner.skip_checks = True
        result = planner.solve(problem)
    assert result.status == Status.UNSUPPORTED_PROBLEM
    assert "hierarchical problems" in result.log_messages[-1].message


# ---------------------------------------------------------------- statuses and options


def chain(n_tasks: int, solvable: bool = True, recursive: bool = False):
    """Tasks t0..t(n-1) in order, each done by action a or b (2^n orders);
    the last is impossible unless ``solvable``; ``recursive`` adds a method
    of t0 that reduces t0 again in the same state (a loop to cut)."""
    pb = HierarchicalProblem("chain")
    done = Fluent("done", BoolType())
    pb.add_fluent(done, default_initial_value=False)
    a, b = InstantaneousAction("a"), InstantaneousAction("b")
    last = InstantaneousAction("last")
    last.add_precondition(done if not solvable else Not(done))
    for act in (a, b, last):
        pb.add_action(act)
    tasks = [pb.add_task(f"t{i}") for i in range(n_tasks)]
    for i, t in enumerate(tasks):
        for act in (a, b):
            m = Method(f"m{i}_{act.name}")
            m.set_task(t)
            m.add_subtask(act)
            pb.add_method(m)
    if recursive:
        m = Method("again")
        m.set_task(tasks[0])
        m.add_subtask(tasks[0])
        pb.add_method(m)
    subtasks = [pb.task_network.add_subtask(t) for t in tasks]
    subtasks.append(pb.task_network.add_subtask(last))
    pb.task_network.set_ordered(*subtasks)
    return pb


def test_an_exhausted_search_proves_unsolvability():
    result = solve(chain(3, solvable=False))
    assert result.status == Status.UNSOLVABLE_PROVEN and result.plan is None


def test_a_search_with_loops_cut_is_unsolvable_incompletely():
    result = solve(chain(2, solvable=False, recursive=True))
    assert result.status == Status.UNSOLVABLE_INCOMPLETELY
    assert "cut by the loop check" in result.log_messages[-1].message


def test_the_depth_bound_stops_the_search_and_is_logged():
    result = solve(chain(2, solvable=False, recursive=True), loop_check=False, max_depth=50)
    assert result.status == Status.UNSOLVABLE_INCOMPLETELY
    assert any("depth limit" in m.message for m in result.log_messages)


def test_the_timeout_stops_a_long_search():
    started = time.perf_counter()
    result = solve(chain(30, solvable=False), timeout=1)
    assert result.status == Status.TIMEOUT and result.plan is None
    assert time.perf_counter() - started < 10


def test_optimize_at_the_timeout_returns_the_best_plan_so_far():
    # the limit counts the conversion too: leave the search some of it on a loaded machine
    result = solve(chain(30), timeout=3, optimize=True)
    assert result.status == Status.TIMEOUT and result.plan is not None
    assert int(result.metrics["plans_found"]) > 1


def test_plan_kind_sequential_returns_the_action_plan():
    problem = cases()["test:htn-go"].problem
    flat = solve(problem, plan_kind="sequential").plan
    hier = solve(problem).plan
    assert isinstance(flat, SequentialPlan)
    assert flat == hier.action_plan == hier.convert_to(PlanKind.SEQUENTIAL_PLAN, problem)


def test_the_output_stream_gets_the_progress():
    out = io.StringIO()
    with OneshotPlanner(name="htn") as planner:
        planner.solve(cases()["test:htn-go"].problem, output_stream=out)
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("htn: plan 1: 6 actions") and "SOLVED_SATISFICING" in lines[-1]


@pytest.mark.parametrize(
    "params, message",
    [
        ({"depth": 3}, "no option 'depth'"),
        ({"max_depth": 0}, "positive integer"),
        ({"optimize": "yes"}, "must be a bool"),
        ({"plan_kind": "partial"}, "plan_kind must be one of"),
        ({"search": "bfs"}, "search must be one of dfs, gbfs, wastar, auto"),
    ],
)
def test_bad_options_are_one_line_usage_errors(params, message):
    with pytest.raises(UPUsageError, match=message):
        OneshotPlanner(name="htn", params=params)
