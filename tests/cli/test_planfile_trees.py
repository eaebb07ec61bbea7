"""Plans keep their task trees: ``htn plan -o`` and ``htn transform -o`` write
each plan's decomposition as comment lines, ``htn run`` executes exactly that
tree (the one ``--plan-index`` chooses) without planning again, and a
corrupted tree is refused at its ``file:line:col``."""

from __future__ import annotations

import builtins
import json
import re

import pytest

from htn.api.run import prepare, read_run_log
from htn.cli.main import main
from htn.jshop.language.terms import Var
from htn.jshop.plans.planfile import read_plan_file
from htn.jshop.plans.tree import PATH_DEPTH
from htn.jshop.search.planner import Planner

from conftest import ROOT, run_htn

DOMAIN = ROOT / "domains" / "domestic.jshop"
BRING = ROOT / "problems" / "bring_object.jshop"
KITCHEN = ROOT / "domains" / "kitchen.jshop"


def htn_main(*args) -> int:
    """The command line in this process; its exit code."""
    with pytest.raises(SystemExit) as ended:
        main([str(a) for a in args])
    return ended.value.code


@pytest.fixture(scope="module")
def three(tmp_path_factory):
    """bring_object's three plans: the same steps, three trees."""
    folder = tmp_path_factory.mktemp("three")
    plan = folder / "plans.txt"
    r = run_htn("plan", DOMAIN, BRING, "-n", "3", "-o", plan, "-f", "json")
    assert r.returncode == 0, r.stderr
    trees = [json.loads(line)["tree"] for line in r.stdout.splitlines()[:3]]
    return plan, trees


@pytest.fixture
def count_planning(monkeypatch):
    """How many searches ``Planner.plans`` starts in this process."""
    calls = []
    real = Planner.plans

    def plans(self, *args, **kwargs):
        calls.append(self.instance)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Planner, "plans", plans)
    return calls


def test_the_plan_text_is_what_jshop2_prints_and_validate_reads_it(three):
    plan, _ = three
    text = plan.read_text()
    assert text.count("; task tree: ") == 3
    # without htn's comment lines, the file is byte for byte the jshop output
    jshop = run_htn("plan", DOMAIN, BRING, "-n", "3", "-f", "jshop").stdout
    assert (
        "".join(line for line in text.splitlines(keepends=True) if not line.startswith(";"))
        == jshop
    )
    r = run_htn("validate", DOMAIN, BRING, plan)
    assert r.returncode == 0 and r.stdout.endswith("3 of 3 plans valid\n"), r.stderr


def test_the_three_plans_share_their_steps_and_differ_in_their_trees(three):
    plan, trees = three
    pf = read_plan_file(str(plan))
    assert len({tuple(p.lines()) for p in pf.plans}) == 1
    chosen = [
        {n["path"]: (n["method_index"], n["branch"]) for n in t["nodes"] if "method" in n}
        for t in trees
    ]
    assert len({json.dumps(c, sort_keys=True) for c in chosen}) == 3


@pytest.mark.parametrize("k", [1, 2, 3])
def test_plan_index_k_executes_the_kth_tree(three, k, count_planning):
    plan, trees = three
    with prepare(plan, robot="symbolic", plan_index=k) as execution:
        dispatcher = execution.begin()
        executed = {
            b.name: (b.htn_task.method_index, b.htn_task.branch)
            for b in dispatcher.root.iterate()
            if hasattr(b, "htn_task") and b.htn_task.method is not None
        }
        leaves = [
            (b.htn_action.node.path, b.htn_action.text)
            for b in dispatcher.root.iterate()
            if hasattr(b, "htn_action")
        ]
        assert execution.execute().ok
    planned = {
        n["path"]: (n["method_index"], n["branch"]) for n in trees[k - 1]["nodes"] if "method" in n
    }
    assert executed == planned
    steps = {n["step"]: n for n in trees[k - 1]["nodes"] if "step" in n}
    assert leaves == [(steps[i]["path"], steps[i]["task"]) for i in sorted(steps)]
    assert count_planning == []  # the tree came from the file


def test_htn_run_on_a_plan_file_never_calls_the_planner(three, count_planning, capsys):
    plan, _ = three
    assert htn_main("run", plan, "--robot", "symbolic", "--plan-index", "2") == 0
    assert count_planning == []
    out, err = capsys.readouterr()
    assert out.splitlines()[-1].startswith("verified: 8 of 8 steps verified") and err == ""


def test_a_plan_file_without_a_tree_runs_as_before_and_says_so(
    three, tmp_path, count_planning, capsys
):
    plan, _ = three
    bare = tmp_path / "bare.txt"
    bare.write_text(
        "".join(
            line
            for line in plan.read_text().splitlines(keepends=True)
            if not re.match(r"; (task tree|\d)", line)
        )
    )
    assert htn_main("run", bare, "--robot", "symbolic") == 0
    out, err = capsys.readouterr()
    assert err == f"{bare}: plan 1 has no task tree: recovered one by planning again\n"
    assert out.splitlines()[-1].startswith("verified: 8 of 8 steps verified")
    assert len(count_planning) == 1  # the search that recovered the tree
    assert htn_main("run", bare, "--robot", "symbolic", "-q") == 0
    assert capsys.readouterr().err == ""  # -q: only the summary


def test_a_hand_written_plan_no_decomposition_gives_runs_as_one_sequence(tmp_path, capsys):
    plan = tmp_path / "hand.txt"
    plan.write_text(
        f"; domain: {DOMAIN}\n; problem: {BRING}\nPlan cost: 1.0\n\n"
        "(!say jenny task_accepted)\n--------------------\n"
    )
    assert htn_main("run", plan, "--robot", "symbolic", "-q") == 0
    assert capsys.readouterr().err == ""  # -q
    with prepare(plan, robot="symbolic") as execution:
        assert execution.notes == [
            f"{plan}: plan 1 has no task tree: planning again found none (50 plans, 5 s), "
            "so it runs as one sequence of actions"
        ]
        assert execution.inputs.tree is None
        assert execution.execute().ok


# ---------------------------------------------------------------- corrupted trees


def _corrupt(plan, tmp_path, old: str, new: str):
    text = plan.read_text()
    assert old in text
    bad = tmp_path / "bad.txt"
    bad.write_text(text.replace(old, new, 1))
    line = next(n for n, t in enumerate(bad.read_text().splitlines(), 1) if new.strip() in t)
    return bad, line


@pytest.mark.parametrize(
    "old,new,token,message",
    [
        (
            "; task tree: 19 nodes",
            "; task tree: 18 nodes",
            "18",
            "the header says 18 nodes, 19 follow",
        ),
        ("; 3 step 1\n", "; 5 step 1\n", "5", "depth 5 does not follow depth 2"),
        ("; 4 step 2\n", "; 4 step 3\n", "3", "step 3 out of order: the plan's next step is 2"),
        (
            "method 1 top_grasp",
            "method 4 top_grasp",
            "method 4",
            "the domain has 3 method(s) for grasp_object, not 4",
        ),
        (
            "method 1 top_grasp",
            "method 1 no_grasp",
            "no_grasp",
            "method 1 of grasp_object has no branch no_grasp",
        ),
        (
            "(go_to jenny counter_front) method",
            "(go_to jenny counter_front x) method",
            "go_to",
            "method 1 of go_to takes 2 argument(s), the task has 3",
        ),
        (
            "(inform jenny task_accepted) method 1",
            "(inform jenny task_accepted) methd 1",
            "methd",
            "expected 'method K LABEL' or 'unreduced' after the task, found 'methd 1",
        ),
        ("; 3 step 1\n", "; 3 (say jenny\n", "(say", "expected 'step N' or a task"),
    ],
)
def test_a_corrupted_tree_is_refused_at_its_line_and_column(
    three, tmp_path, capsys, old, new, token, message
):
    plan, _ = three
    bad, line = _corrupt(plan, tmp_path, old, new)
    col = bad.read_text().splitlines()[line - 1].find(token) + 1
    assert htn_main("run", bad, "--robot", "symbolic") == 2
    first = capsys.readouterr().err.splitlines()[0]
    assert first.startswith(f"{bad}:{line}:{col}: task tree: {message}"), first
    # validate reads the JSHOP2 plan text only: the plans are still valid
    assert htn_main("validate", DOMAIN, BRING, bad) == 0


def test_a_tree_that_misses_a_step_is_refused(three, tmp_path, capsys):
    plan, _ = three
    text = plan.read_text()
    lines = text.splitlines(keepends=True)
    head = next(i for i, t in enumerate(lines) if t.startswith("; task tree: "))
    last_step = next(i for i in range(len(lines)) if lines[i] == "; 5 step 8\n")
    del lines[last_step]
    lines[head] = "; task tree: 18 nodes\n"
    bad = tmp_path / "bad.txt"
    bad.write_text("".join(lines))
    assert htn_main("run", bad, "--robot", "symbolic") == 2
    assert capsys.readouterr().err.startswith(
        f"{bad}:{head + 1}:1: task tree: the tree has 7 of the plan's 8 steps"
    )


# ---------------------------------------------------------------- transform, variables, depth


@pytest.mark.slow
def test_transform_writes_the_transformed_tree_and_run_executes_it(tmp_path, count_planning):
    out = tmp_path / "t.txt"
    r = run_htn("transform", KITCHEN, ROOT / "problems" / "tray_three.jshop", "-o", out, "--json")
    assert r.returncode == 0, r.stderr
    tree = json.loads(r.stdout)["tree"]["nodes"]
    count_planning.clear()  # htn transform plans (in this process): only run counts
    with prepare(out, robot="symbolic") as execution:
        root = execution.begin().root
        executed = {
            b.name: (b.htn_task.method_index, b.htn_task.branch)
            for b in root.iterate()
            if hasattr(b, "htn_task") and b.htn_task.method
        }
        assert execution.execute().ok
    assert executed == {n["path"]: (n["method_index"], n["branch"]) for n in tree if "method" in n}
    assert count_planning == []


def test_a_variable_left_in_a_task_reads_back_as_the_same_variable(tmp_path):
    plan = tmp_path / "plan.txt"
    assert (
        run_htn(
            "plan", KITCHEN, ROOT / "problems" / "tray_three.jshop", "-o", plan, "--timeout", "60"
        ).returncode
        == 0
    )
    assert "?arm?3" in plan.read_text()
    fetching = next(n for n in read_plan_file(str(plan)).tree(0).walk() if n.name == "fetching")
    var = fetching.args[-1]
    assert isinstance(var, Var) and (var.name, var.index) == ("?arm", 3)


def test_a_deep_tree_is_written_in_linear_size(tmp_path):
    n = 600
    domain, problem = tmp_path / "d.jshop", tmp_path / "p.jshop"
    domain.write_text(
        "(defdomain deep ((:operator (!a ?x) ((p ?x)) ((p ?x)) ())\n"
        "  (:method (all) ((p ?x)) ((!a ?x) (all)) () ())))"
    )
    problem.write_text(
        "(defproblem p deep (" + " ".join(f"(p {i})" for i in range(n)) + ") ((all)))"
    )
    plan = tmp_path / "plan.txt"
    assert run_htn("plan", domain, problem, "-o", plan).returncode == 0
    pf = read_plan_file(str(plan))
    tree = pf.tree(0)
    nodes = [t for t in pf.lines if re.match(r"; \d", t)]
    assert len(nodes) == 2 * n + 1 and max(map(len, nodes)) < 40  # depths, not indentation
    assert len([x for x in tree.walk() if x.step is not None]) == n
    # read back, paths stop at PATH_DEPTH levels as the planner's do (tree.py)
    deepest = max(tree.walk(), key=lambda x: x.path.count("/"))
    assert deepest.path.count("/") == PATH_DEPTH - 1
    assert sum(len(x.path) for x in tree.walk()) < 50 * n  # linear: 720k characters before


# ---------------------------------------------------------------- the plan file is read once


def test_htn_run_reads_the_plan_file_once_also_from_a_log(three, tmp_path, monkeypatch):
    plan, _ = three
    log = tmp_path / "run.jsonl"
    opened = []
    real_open = builtins.open

    def counting_open(file, *args, **kwargs):
        if str(file) == str(plan):
            opened.append(file)
        return real_open(file, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", counting_open)
    assert htn_main("run", plan, "--robot", "symbolic", "-q", "--log", log) == 0
    assert len(opened) == 1
    opened.clear()
    assert htn_main("run", "--from-log", log, "-q") == 0
    assert len(opened) == 1
    logged = read_run_log(log)
    assert logged.plan.sha256 == json.loads(log.read_text().splitlines()[0])["plan_sha256"]
