"""The goal-chain cut of the heuristic search (:mod:`htn.jshop.search.goal_chain`):
it cuts a network whose refinements cannot make the goal's chain true in their
order; neither it nor the goal-reachability cut (:mod:`htn.jshop.search.goal_reach`)
cuts a node on a plan's path."""

from __future__ import annotations

import re

import pytest

from htn.jshop.readers.load import load_inputs
from htn.jshop.search import best_first, grounding
from htn.jshop.search.best_first import BestFirst
from htn.jshop.search.goal_chain import GoalChain
from htn.jshop.search.goal_cuts import chained
from htn.jshop.search.goal_reach import GoalReach
from htn.jshop.search.task_networks import body_items, replace

from conftest import SHARED

CORPUS = SHARED / "corpus"

# Two observed actions that must happen in order (p1 needs l1 and gives l2, p2
# needs l2 and gives l3, the goal). The top task's first method does a before
# b; with the written order, b's p2 comes first and can never apply.
DOMAIN = """(define (domain chain) (:requirements :hierarchy)
  (:predicates (l1) (l2) (l3) (busy))
  (:task top :parameters ()) (:task a :parameters ()) (:task b :parameters ())
  (:method m_wrong :parameters () :task (top)
    :ordered-subtasks (and (b) (a)))
  (:method m_right :parameters () :task (top)
    :ordered-subtasks (and (a) (b)))
  (:method m_a :parameters () :task (a) :ordered-subtasks (and (p1)))
  (:method m_b :parameters () :task (b) :ordered-subtasks (and (work) (p2)))
  (:action p1 :parameters () :precondition (l1) :effect (and (l2) (not (l1))))
  (:action p2 :parameters () :precondition (l2) :effect (and (l3) (not (l2))))
  (:action work :parameters () :effect (busy)))
"""
PROBLEM = """(define (problem one) (:domain chain)
  (:htn :ordered-subtasks (and (top)))
  (:init (l1))
  (:goal (l3)))
"""


def _write(tmp_path):
    (tmp_path / "d.hddl").write_text(DOMAIN)
    (tmp_path / "p.hddl").write_text(PROBLEM)
    dom, prob = load_inputs(str(tmp_path / "d.hddl"), str(tmp_path / "p.hddl"))
    return dom, prob.instances[0]


def test_the_order_of_a_network_decides(tmp_path):
    dom, inst = _write(tmp_path)
    model = grounding.ground(dom, inst)
    cut = GoalChain(model)
    assert cut.active
    names = {model.tasks[t][0]: t for t in range(len(model.tasks))}
    a, b = names["a"], names["b"]
    # every chain action is reachable from both orders: only the order differs
    assert cut.ok(model.init, (a, b))
    assert not cut.ok(model.init, (b, a))
    assert cut.after(b, cut._small(model.init)) is None
    # once p1 is done, b alone can reach the goal
    assert cut.ok(1 << model.bits[("l2", ())], (b,))


MONROE = "ipc2020-to-hard/Monroe-Partially-Observable/pfile13-p-0096-clear-road-wreck-9"


@pytest.mark.corpus
@pytest.mark.slow
def test_the_cut_lets_gbfs_solve_a_plan_recognition_instance(tmp_path):
    """GBFS with RC-add alone is lost in this instance's 198 top-level
    methods (the right one is the last, with the highest estimate); with
    the cut it plans in a few hundred expansions."""
    domain, problem = CORPUS / f"{MONROE}-domain.hddl", CORPUS / f"{MONROE}.hddl"
    if not domain.is_file():
        pytest.skip(f"{domain} not found")
    dom, prob = load_inputs(str(domain), str(problem))
    search = BestFirst(dom, prob.instances[0])
    plan = next(p for p in search.plans(timeout=120) if p is not None)
    assert search.stats.goal_cuts > 0 and search.stats.expansions < 5000
    assert search.stats.as_dict()["goal_cuts"] == search.stats.goal_cuts
    # the observed actions are in the plan, in their order
    observed = [
        int(re.match(r"!p_(\d+)", s.name).group(1)) for s in plan.steps if s.name.startswith("!p_")
    ]
    assert observed == [1, 2, 3, 4, 5, 6]


class _Moves(BestFirst):
    """A search that keeps its plan's moves ``(path, action or method)``."""

    def _plan(self, nodes, k, index):
        self.moves, i = [], k
        while i > 0:
            self.moves.append(nodes[i][3])
            i = nodes[i][2]
        self.moves.reverse()
        return super()._plan(nodes, k, index)


# instances whose goal has a chain, planned by GBFS without the cut in seconds
SOUND = [
    ("ipc2020-to/Blocksworld-GTOHP/domain.hddl", "ipc2020-to/Blocksworld-GTOHP/p05.hddl"),
    ("ipc2020-to/Depots/domain.hddl", "ipc2020-to/Depots/p05.hddl"),
    ("ipc2020-to/Towers/domain.hddl", "ipc2020-to/Towers/pfile_05.hddl"),
    ("ipc-po/UM-Translog/domain.hddl", "ipc-po/UM-Translog/06-A-AutoTruck.hddl"),
    ("ipc-po/Woodworking/domain.hddl", "ipc-po/Woodworking/01--p01-complete.hddl"),
    ("ipc2023-to/Lamps/domain.hddl", "ipc2023-to/Lamps/pfile02.pddl"),
    # a fold that reads a new pair where it read a smaller one: a first
    # version re-queued readers on a smaller evaluation and never ended
    ("ipc2023-to/Lamps/domain.hddl", "ipc2023-to/Lamps/pfile04.pddl"),
    # two unordered tasks whose refinements must interleave (turnA, turnB)
    ("ipc-po/PCP/p-pcp11-domain.hddl", "ipc-po/PCP/p-pcp11.hddl"),
]


@pytest.mark.corpus
@pytest.mark.parametrize("make", [GoalChain, GoalReach], ids=["chain", "reach"])
@pytest.mark.parametrize(
    "domain,problem", SOUND, ids=["-".join(p.split("/")[1:]).rsplit(".", 1)[0] for _, p in SOUND]
)
def test_no_node_of_a_plan_found_without_the_cut_is_cut(domain, problem, make, monkeypatch):
    if not (CORPUS / domain).is_file():
        pytest.skip(f"{CORPUS / domain} not found")
    dom, prob = load_inputs(str(CORPUS / domain), str(CORPUS / problem))
    inst = prob.instances[0]
    model = grounding.ground(dom, inst)
    monkeypatch.setattr(best_first, "goal_cuts", lambda m: None)
    search = _Moves(dom, inst)
    search._prepared(model)
    plan = next(p for p in search.plans(timeout=60) if p is not None)
    cut = make(model)
    assert cut.active
    # replay the plan's moves from the root, as the search made them
    net = body_items(model.roots, model.root_order)
    state = model.init
    checked = 0
    for path, what in search.moves:
        assert cut.ok(state, net), f"a node on the plan's path is cut after {checked} moves"
        checked += 1
        if hasattr(what, "op"):
            state = best_first._apply(what, state)
            net = replace(net, path, ())
        else:
            net = replace(net, path, body_items(what.body, what.order))
    assert not net and checked > len(plan.steps)


@pytest.mark.corpus
@pytest.mark.parametrize(
    "domain,problem,arms",
    [
        (
            "ipc-po/PCP/p-pcp11-domain.hddl",
            "ipc-po/PCP/p-pcp11.hddl",
            ["gbfs-serial", "wastar", "gbfs-tdg"],  # partially ordered: the serial GBFS too
        ),
        (
            "ipc2020-to/Childsnack/domain.hddl",
            "ipc2020-to/Childsnack/p05.hddl",
            ["wastar", "gbfs-tdg"],  # TDG_m without a goal chain, at a third of the share
        ),
    ],
    ids=["goal-chain", "no-goal"],
)
def test_auto_adds_a_tdg_search_with_the_cut_where_the_goal_has_a_chain(domain, problem, arms):
    if not (CORPUS / domain).is_file():
        pytest.skip(f"{CORPUS / domain} not found")
    from htn.jshop.search.portfolio import Portfolio

    dom, prob = load_inputs(str(CORPUS / domain), str(CORPUS / problem))
    auto = Portfolio(dom, prob.instances[0])
    auto.gbfs.prepare()
    more = auto._on_model()
    assert more == arms and auto.started == 2 + len(arms)
    for s in map(auto.member, more):
        assert s.model is auto.gbfs.model and s.cut is auto.gbfs.cut
    assert auto.wastar.h is auto.gbfs.h
    assert auto.tdg.heuristic_name == "tdg"
    assert auto._share("gbfs-tdg") == (3 if chained(auto.tdg.cut) else 1)
    if "gbfs-serial" in arms:
        assert chained(auto.tdg.cut)
    else:
        assert not chained(auto.tdg.cut) and auto._share("gbfs-tdg") == 1
        plan = next(p for p in auto.tdg.plans(timeout=60) if p is not None)
        assert plan.steps


@pytest.mark.corpus
def test_auto_shares_cpu_by_the_shares_and_a_late_search_joins_at_once():
    # Factories-simple pfile13: grounding takes a tenth of a second, and
    # depth-first search without its guards (needs.py, threats.py; with them
    # it plans this in about 1.3 s) is stuck, so every search runs for the
    # whole limit
    domain = SHARED / "corpus" / "ipc2020-to-hard" / "Factories-simple"
    if not (domain / "pfile13.hddl").is_file():
        pytest.skip(f"{domain} not found")
    from htn.jshop.search.portfolio import SLICE, Portfolio

    dom, prob = load_inputs(str(domain / "domain.hddl"), str(domain / "pfile13.hddl"))
    auto = Portfolio(dom, prob.instances[0], guards=False)
    assert next(auto.plans(timeout=6), None) is None
    assert set(auto.spent) == {"dfs", "gbfs", "wastar", "gbfs-tdg"}
    # CPU seconds per share: each turn adds SLICE to one of them
    pace = {s: auto.spent[s] / auto._share(s) for s in auto.spent}
    # the late ones had their first turns as soon as GBFS had grounded (in
    # its first turn), and from then on all kept pace: a turn apart at
    # most, and a slice's overshoot
    assert auto.turns[:4] == ["dfs", "gbfs", "wastar", "gbfs-tdg"], auto.turns
    assert max(pace.values()) - min(pace.values()) < 2 * SLICE, pace


@pytest.mark.corpus
def test_a_depth_first_search_that_never_backtracked_gets_the_others_share():
    # the rule, on Towers pfile_05's portfolio (pfile_13: 24,590 expansions
    # without a backtrack; pfile_17, 131,071 moves, planned within 30 s by it)
    towers = SHARED / "corpus" / "ipc2020-to" / "Towers"
    if not (towers / "pfile_05.hddl").is_file():
        pytest.skip(f"{towers} not found")
    from htn.jshop.search.portfolio import STRAIGHT, Portfolio

    dom, prob = load_inputs(str(towers / "domain.hddl"), str(towers / "pfile_05.hddl"))
    auto = Portfolio(dom, prob.instances[0])
    live = ["dfs", "gbfs", "wastar"]
    stats = auto.dfs.stats
    stats.expansions = STRAIGHT - 1
    assert auto._share("dfs", live) == 1  # not far enough yet
    stats.expansions = STRAIGHT
    assert auto._share("dfs", live) == 3 + 1  # straight: as much as the others together
    stats.backtracks = 1
    assert auto._share("dfs", live) == 1  # once it backtracked, it is one search of four
    plan = next(auto.plans(timeout=60), None)
    assert plan is not None and auto.stats.found_by == "dfs"
