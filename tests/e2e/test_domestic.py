"""The domestic robot domain: the paper's Table 1, golden plans and task trees."""

from __future__ import annotations

import json

import pytest

from htn.jshop import Planner, load_domain, load_problem

from conftest import CORPUS, ROOT, needs_corpus, run_htn

DOMAIN = ROOT / "domains" / "domestic.jshop"


def plans_of(problem: str, trees: bool = True):
    dom = load_domain(str(DOMAIN))
    prob = load_problem(str(ROOT / "problems" / f"{problem}.jshop"))
    return list(Planner(dom, prob.instances[0], record_trees=trees).plans())


def test_table1_figures_from_htn_stats():
    result = run_htn("stats", "--json", "--repeat", "1")
    assert result.returncode == 0, result.stderr
    rows = {r["problem"].split("/")[-1]: r for r in json.loads(result.stdout)["scenarios"]}
    bring, guide = rows["bring_object.jshop"], rows["guide_robot.jshop"]
    assert (bring["plans"], bring["distinct_plans"], bring["min_length"]) == (3, 1, 8)
    assert (guide["plans"], guide["distinct_plans"], guide["min_length"]) == (1, 1, 5)
    for r in (bring, guide):
        assert (r["methods"], r["operators"]) == (13, 7)
        assert r["plan_ms"] > 0


def test_htn_stats_for_given_problems():
    result = run_htn(
        "stats", DOMAIN, ROOT / "problems" / "bring_two.jshop", "--json", "--repeat", "2"
    )
    assert result.returncode == 0, result.stderr
    (row,) = json.loads(result.stdout)["scenarios"]
    assert row["plans"] == 6 and row["distinct_plans"] == 1 and row["min_length"] == 16


def test_htn_stats_table_shows_paper_figures():
    result = run_htn("stats", "--repeat", "1")
    assert result.returncode == 0
    assert "paper 3 s" in result.stdout and "paper 1.5 s" in result.stdout
    assert "13 / 7" in result.stdout


def test_htn_stats_needs_a_problem_with_a_domain():
    result = run_htn("stats", DOMAIN)
    assert result.returncode == 2
    assert "PROBLEM" in result.stderr


@pytest.mark.parametrize("problem", ["bring_object", "guide_robot"])
def test_golden_plans(problem, golden):
    result = run_htn(
        "plan", DOMAIN, ROOT / "problems" / f"{problem}.jshop", "--all", "--format", "jshop"
    )
    assert result.returncode == 0, result.stderr
    golden(f"{problem}.plans.txt", result.stdout)


@pytest.mark.parametrize("problem", ["bring_object", "guide_robot"])
def test_golden_trees(problem, golden):
    text = "\n".join(p.tree.to_text() for p in plans_of(problem))
    golden(f"{problem}.tree.txt", text)


def test_three_bring_plans_differ_only_in_decomposition():
    plans = plans_of("bring_object")
    assert len({tuple(p.lines()) for p in plans}) == 1
    grasp = [p.tree.find("bring_object/fetch_object/grasp_object") for p in plans]
    assert [(g.method_index, g.branch) for g in grasp] == [
        (0, "top_grasp"),
        (1, "side_grasp"),
        (2, grasp[2].branch),
    ]
    assert grasp[2].args == ("pringles", "kitchen_counter")  # the two-parameter method


def test_tree_paths_unique_and_stable():
    first = [[n.path for n in p.tree.walk()] for p in plans_of("bring_two")]
    again = [[n.path for n in p.tree.walk()] for p in plans_of("bring_two")]
    assert first == again
    for paths in first:
        paths = paths[1:]  # the root has the empty path
        assert len(paths) == len(set(paths))
    assert "bring_object :call 2/fetch_object/grasp_object/!grasp" in first[0]


def test_leaves_of_each_tree_are_its_plan():
    for p in plans_of("bring_two"):
        leaves = p.tree.leaves()
        assert [n.task for n in leaves] == p.lines()
        assert [n.step for n in leaves] == list(range(len(p.steps)))


@needs_corpus
def test_blocks_smallproblem_every_tree_matches_its_plan():
    folder = CORPUS / "blocks-smallproblem"
    dom = load_domain(str(folder / "blocks"))
    prob = load_problem(str(folder / "smallproblem"))
    plans = list(Planner(dom, prob.instances[0], record_trees=True).plans())
    assert len(plans) == 4
    for p in plans:
        leaves = p.tree.leaves()
        assert [n.task for n in leaves] == p.lines()
        assert [n.step for n in leaves] == list(range(len(p.steps)))
    # each plan's tree is its own: different plans, different trees
    assert len({p.tree.to_text() for p in plans}) == 4


def test_tree_never_shows_backtracked_branches():
    """A branch that fails after reducing must not leave its steps in the tree."""
    from htn.jshop import parse_text

    dom = parse_text("""
    (defdomain d (
      (:operator (!a) () () ((did-a)))
      (:operator (!b) ((ok)) () ())
      (:operator (!c) () () ())
      (:method (top) () ((try) (!c)))
      (:method (try) () ((!a) (!b)))
      (:method (try) () ((!c)))))""")
    prob = parse_text("(defproblem p d () ((top)))")
    (plan,) = Planner(dom, prob.instances[0], record_trees=True).plans()
    assert plan.lines() == ["(!c)", "(!c)"]
    text = plan.tree.to_text()
    assert "(!a)" not in text and "(!b)" not in text
    assert plan.tree.find("top/try").method_index == 1


def test_cli_tree_dot_and_json(tmp_path):
    dot = tmp_path / "tree.dot"
    result = run_htn(
        "plan", DOMAIN, ROOT / "problems" / "guide_robot.jshop", "--format", "json", "--dot", dot
    )
    assert result.returncode == 0, result.stderr
    plan, stats = [json.loads(line) for line in result.stdout.splitlines()]  # JSON Lines
    assert plan["type"] == "plan" and stats["type"] == "stats" and stats["plans_found"] == 1
    root, top = plan["tree"]["nodes"][:2]
    assert root["parent"] is None and top["parent"] == root["id"]
    assert top["path"] == "guide_robot" and top["method"] == "guide_robot"
    text = dot.read_text()
    assert text.startswith("digraph task_tree {") and text.rstrip().endswith("}")
    assert text.count("->") == sum(1 for _ in text.splitlines() if "->" in _)
    rich_result = run_htn(
        "plan", DOMAIN, ROOT / "problems" / "guide_robot.jshop", "--format", "text", "--tree"
    )
    assert ":call 2" in rich_result.stdout and "step 5" in rich_result.stdout


@pytest.mark.parametrize(
    "problem,length,first_step",
    [
        ("bring_coke", 8, "(!say jenny task_accepted)"),
        ("bring_two", 16, "(!say jenny task_accepted)"),
        ("bring_to_table", 8, "(!say jenny task_accepted)"),
        ("guide_to_sofa", 5, "(!move_base jenny home_base entrance)"),
    ],
)
def test_methods_are_reused_by_other_problems(problem, length, first_step):
    plans = plans_of(problem, trees=False)
    assert plans and all(len(p.steps) == length for p in plans)
    assert plans[0].lines()[0] == first_step
    if problem == "bring_to_table":
        assert "(!place jenny pringles coffee_table)" in plans[0].lines()
