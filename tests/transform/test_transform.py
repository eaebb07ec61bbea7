"""Plan transformations: applicability rules (JSHOP2 axioms), the framework API,
the three rules, and rollback of rewrites that break a plan or cost more."""

from __future__ import annotations

import json

import pytest

from htn.jshop import Planner, load_domain, load_problem
from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.transform import rules
from htn.transform.framework import Framework, Unit, Workspace, navigation_distance

from conftest import ROOT, run_htn

DOMAIN = str(ROOT / "domains" / "kitchen.jshop")
PROBLEMS = ROOT / "problems"


def workspace(problem: str, text: str | None = None) -> Workspace:
    dom = load_domain(DOMAIN)
    if text is not None:
        path = ROOT / "problems" / "transport_four.jshop"  # for a position only
        from htn.jshop.readers.load import parse_text

        prob = parse_text(text, str(path))
    else:
        prob = load_problem(str(PROBLEMS / f"{problem}.jshop"))
    return Workspace.from_problem(dom, prob.instances[0])


def framework() -> Framework:
    fw = Framework()
    rules.register(fw)
    return fw


def replay_is_valid(ws: Workspace) -> bool:
    """Independent check: every step applies in sequence from the initial state."""
    checker = Planner(ws.domain, S.ProblemInstance(ws.instance.state, S.TaskList([])))
    return all(checker.apply_step(s.name, s.args) for s in ws.plan.steps)


TWO_TARGETS = """(defproblem p kitchen
  ((area kitchen_island 0.0 2.0) (area sink_area 3.5 -0.5) (area table 0.0 -3.0)
   (area start 1.5 0.0) (at milk kitchen_island) (at cup kitchen_island)
   (robot-at start) (free left) (free right))
  ((transporting milk kitchen_island sink_area) (transporting cup kitchen_island table)))"""


def test_both_hands_rule_applies_to_same_areas_only():
    fw = framework()
    pairs = fw.query(workspace("transport_four"), "(both-hands ?first ?second)")
    assert {"first": "transporting :call 1", "second": "transporting :call 2"} in pairs
    assert len(pairs) == 6  # every ordered pair of the four transports
    assert fw.query(workspace("", TWO_TARGETS), "(both-hands ?first ?second)") == []


def test_container_rule_applies_only_to_a_shared_container():
    fw = framework()
    shared = fw.query(workspace("set_table_and_clean_up"), "(container-shared ?t ?c)")
    assert {s["t"] for s in shared} == {"transporting :call 3", "transporting :call 4"}
    assert {s["c"] for s in shared} == {"drawer"}
    assert fw.query(workspace("transport_four"), "(container-shared ?t ?c)") == []


def test_tray_needs_more_than_two_transports():
    ws = workspace("tray_three")
    fw = framework()
    assert len(fw.query(ws, "(tray-transport ?t ?tray ?from ?to)")) == 3
    two = workspace(
        "",
        """(defproblem p kitchen
      ((area kitchen_island 0.0 0.0) (area sink_area 1.2 0.6) (area start 0.6 -0.8)
       (at bowl kitchen_island) (at cup kitchen_island) (tray tray1 kitchen_island)
       (robot-at start) (free left) (free right))
      ((transporting bowl kitchen_island sink_area) (transporting cup kitchen_island sink_area)))""",
    )
    fw.disable_transformation("both-hands")
    fw.apply_all_transformations(two)
    assert two.log == []  # the rule matched two transports; the tray was not used


@pytest.mark.slow
def test_priorities_and_enable_disable():
    fw = framework()
    assert [t.name for t in fw.transformations] == ["tray", "container", "both-hands"]
    with pytest.raises(HtnError, match="cycle"):  # tray > container > both-hands > tray
        fw.prioritize_transformation("both-hands", "tray")
    assert [t.name for t in fw.transformations] == ["tray", "container", "both-hands"]
    fw.prioritize_transformation("both-hands", "container")  # replaces the reverse priority
    assert [t.name for t in fw.transformations] == ["tray", "both-hands", "container"]
    fw2 = framework()
    fw2.disable_transformation("both-hands")
    ws = fw2.apply_all_transformations(workspace("transport_four"))
    assert ws.log == []
    fw2.enable_transformation(rules.both_hands)
    ws = fw2.apply_all_transformations(workspace("transport_four"))
    assert [r for r, status, _ in ws.log] == ["both-hands", "both-hands"]
    with pytest.raises(HtnError):
        fw2.disable_transformation("no-such-rule")


@pytest.mark.slow
def test_transport_four_gets_both_hands_twice_and_stays_valid():
    ws = workspace("transport_four")
    before = navigation_distance(ws.instance, ws.plan)
    framework().apply_all_transformations(ws)
    assert [(r, s) for r, s, _ in ws.log] == [("both-hands", "applied")] * 2
    assert navigation_distance(ws.instance, ws.plan) < 0.6 * before
    assert replay_is_valid(ws)
    holding = max_holding = 0
    for s in ws.plan.steps:
        holding += s.name.startswith("!grasp") - (s.name == "!place")
        max_holding = max(max_holding, holding)
    assert max_holding == 2  # both arms are used at once


@pytest.mark.slow
def test_set_table_and_clean_up_uses_all_three_rules():
    ws = workspace("set_table_and_clean_up")
    framework().apply_all_transformations(ws)
    assert [r for r, s, _ in ws.log if s == "applied"] == ["tray", "container", "both-hands"]
    lines = ws.plan.lines()
    assert lines.count("(!open drawer)") == 1 and lines.count("(!close drawer)") == 1
    assert "(!lift-tray tray1)" in lines
    assert replay_is_valid(ws)


def test_tray_three_adds_actions():
    ws = workspace("tray_three")
    n = len(ws.plan.steps)
    framework().apply_all_transformations(ws)
    assert ws.log[0][0] == "tray" and len(ws.plan.steps) > n
    assert replay_is_valid(ws)


def test_a_rewrite_that_breaks_the_plan_is_rolled_back():
    fw = Framework()

    def deliver_before_fetch(ws, schemas):
        path = schemas[0]["t"]
        unit = ws.unit_of(path)
        obj, src, dst = unit.tasks[0].args
        new = Unit([S.TaskAtom("delivering", (obj, dst, "left"))], [path], "broken")
        ws.units = [new if u is unit else u for u in ws.units]
        return f"deliver {obj} first", [path]

    fw.register_transformation(deliver_before_fetch, "(transport ?t ?o ?f ?d ?k)", "broken")
    ws = workspace("transport_four")
    original = ws.plan.lines()
    fw.apply_all_transformations(ws)
    assert all(status == "rolled back" for _, status, _ in ws.log) and len(ws.log) == 4
    assert "no valid plan" in ws.log[0][2]
    assert ws.plan.lines() == original


@pytest.mark.slow
def test_a_costlier_rewrite_is_rolled_back():
    fw = Framework()

    def detour(ws, schemas):
        path = schemas[0]["t"]
        unit = ws.unit_of(path)
        new = Unit([S.TaskAtom("go-to", ("start",)), *unit.tasks], [path], "detour")
        ws.units = [new if u is unit else u for u in ws.units]
        return f"detour before {path}", [path]

    fw.register_transformation(detour, "(transport ?t ?o ?f ?d ?k)", "detour")
    ws = workspace("transport_four")
    before = navigation_distance(ws.instance, ws.plan)
    fw.apply_all_transformations(ws)
    rolled = [d for _, s, d in ws.log if s == "rolled back"]
    assert len(rolled) == 3 and all("navigation" in d for d in rolled)
    # the first detour (to where the robot starts) costs nothing and is kept
    assert ws.log[0][1] == "applied"
    assert navigation_distance(ws.instance, ws.plan) == before


@pytest.mark.slow
def test_htn_transform_cli(tmp_path):
    out = tmp_path / "plan.txt"
    r = run_htn("transform", DOMAIN, PROBLEMS / "set_table_and_clean_up.jshop", "--json", "-o", out)
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["applied"] == ["tray", "container", "both-hands"]
    assert doc["transformed"]["navigation"] < doc["original"]["navigation"]
    text = out.read_text()
    assert text.startswith("; htn plan file") and text.splitlines().count("(!open drawer)") == 1
    bad = run_htn("transform", DOMAIN, PROBLEMS / "tray_three.jshop", "--rules", "nope")
    assert bad.returncode == 2 and "unknown rule" in bad.stderr


# ------------------------------------------------------------------ projection and evaluate


def test_projection_is_deterministic_and_monitored():
    from htn.executor.config import load_retries
    from htn.robot.projection import FailureRates
    from htn.transform.projection import project

    ws = workspace("transport_four")
    retries = load_retries(DOMAIN)
    runs = [
        project(ws.domain, ws.instance, ws.plan.steps, seed, retries=retries) for seed in range(40)
    ]
    again = project(ws.domain, ws.instance, ws.plan.steps, 7, retries=retries)
    assert again == runs[7]  # same seed, same run
    assert all(r["result"] == "verified" for r in runs)
    clean = project(ws.domain, ws.instance, ws.plan.steps, 1, FailureRates.none(), retries)
    assert clean["failures"] == 0 and clean["actions"] == len(ws.plan.steps)
    # a failure leaves the effect absent: without retries, the run stops aborted
    broken = project(
        ws.domain, ws.instance, ws.plan.steps, 1, FailureRates(grasp=1.0, grasp_busy=1.0), {}
    )
    assert broken["result"] == "aborted"


@pytest.mark.slow
def test_evaluate_reproduces_the_papers_findings():
    from htn.api.evaluate import evaluate

    four = evaluate(PROBLEMS / "transport_four.jshop", domain=DOMAIN, runs=120, seed=0).metrics
    assert -40 < four["navigation"]["change_pct"] < -20 and four["navigation"]["p_value"] < 1e-3
    assert abs(four["manipulation"]["change_pct"]) < 10
    assert four["failures"]["change_pct"] > 0
    tray = evaluate(PROBLEMS / "tray_three.jshop", domain=DOMAIN, runs=120, seed=0).metrics
    assert tray["actions"]["change_pct"] > 20 and -15 < tray["navigation"]["change_pct"] < 0


@pytest.mark.slow
def test_task_tree_annotated_by_a_projected_run():
    from htn.executor.config import load_retries
    from htn.transform.projection import projected_tree

    ws = workspace("transport_four")
    framework().apply_all_transformations(ws)
    tree = ws.annotated_tree()
    first = tree.children[0]
    assert first.code_replacement and first.code_replacement[0].startswith("(searching milk")
    tree, run = projected_tree(
        ws.domain, ws.instance, ws.plan, seed=3, retries=load_retries(DOMAIN)
    )
    assert run["result"] == "verified"
    assert all(n.outcome == "verified" for n in tree.walk() if n is not tree)
    d = tree.to_dict()["nodes"][1]  # the root's first child
    assert d["outcome"] == "verified" and "code_replacement" in d and "path" in d


def test_an_area_without_numeric_coordinates_is_an_error_at_its_atom(tmp_path):
    """Found by the long fuzz run: the projection read an area's coordinates
    with float(), a traceback for ``transform``, ``run --robot projection``
    and ``evaluate``."""
    kitchen = ROOT / "domains" / "kitchen.jshop"
    text = (ROOT / "problems" / "set_table_and_clean_up.jshop").read_text()
    assert "(area sink_area 3.5 -0.5)" in text
    problem = tmp_path / "p.jshop"
    problem.write_text(text.replace("(area sink_area 3.5 -0.5)", "(area sink_area and -0.5)"))
    plan = tmp_path / "plan.txt"
    runs = [
        ["transform", kitchen, problem],
        ["evaluate", problem, "--domain", kitchen, "--runs", "2"],
    ]
    if run_htn("plan", kitchen, problem, "-o", plan).returncode == 0:
        runs.append(["run", plan, "--robot", "projection"])
    for argv in runs:
        r = run_htn(*argv)
        assert r.returncode == 2 and "Traceback" not in r.stderr, (argv, r.stderr)
        assert r.stderr.startswith(f"{problem}:6:35: area: expected a number, got and"), (
            argv,
            r.stderr,
        )


def test_the_projection_refuses_an_area_atom_with_too_few_arguments():
    from htn.robot.projection import world_from_atoms

    atom = S.Atom("area", ("sink_area", 3.5), S.Pos("p.jshop", 6, 3))
    with pytest.raises(HtnError) as err:
        world_from_atoms([atom])
    assert str(err.value).startswith("p.jshop:6:3: (area ...) has too few arguments")
