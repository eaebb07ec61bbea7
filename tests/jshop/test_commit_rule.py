"""The heuristic search's rule that decomposing a task whose methods test
nothing of the state is no choice point (:func:`htn.jshop.search.best_first.committed`):
it finds a plan exactly where the search over every move does, on random
partially ordered problems, and every plan it finds passes htn's
decomposition check and, when the binary is there, the competition's
verifier (pandaPIparser)."""

from __future__ import annotations

import subprocess
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from htn.api.inputs import function_table, read_inputs
from htn.jshop.checks.ipc_verify import verify_ipc_text
from htn.jshop.plans.ipc import ipc_text
from htn.jshop.search.best_first import BestFirst, committed

from conftest import SHARED

PANDA = SHARED / "tools" / "pandaPIparser" / "pandaPIparser"
FACTS = ["p0", "p1", "p2", "p3"]
ACTIONS = 4


def test_one_free_task_is_the_only_move():
    front = [((0,), 7), ((1,), 8), ((2,), 9)]
    assert committed(front, frozenset({8, 9})) == [((1,), 8)]
    assert committed(front, frozenset()) == front
    assert committed(front[:1], frozenset({7})) == front[:1]


# a method whose precondition only a parallel action makes true: deciding its
# task first would lose the plan, so the rule leaves such tasks alone
LATER = """(define (domain later)
  (:requirements :hierarchy)
  (:predicates (ready) (done))
  (:task t :parameters ())
  (:task u :parameters ())
  (:method m :parameters () :task (t) :precondition (ready)
    :ordered-subtasks (and (finish)))
  (:method mu :parameters () :task (u) :ordered-subtasks (and (prepare)))
  (:action prepare :parameters () :precondition () :effect (ready))
  (:action finish :parameters () :precondition (ready) :effect (done)))
"""
LATER_PROBLEM = """(define (problem later1) (:domain later)
  (:htn :parameters () :subtasks (and (s0 (t)) (s1 (u))))
  (:init)
  (:goal (done)))
"""


def _literal(draw, negative=True):
    fact = draw(st.sampled_from(FACTS))
    return f"(not ({fact}))" if negative and draw(st.booleans()) else f"({fact})"


def _conj(items):
    return "()" if not items else items[0] if len(items) == 1 else f"(and {' '.join(items)})"


def _network(draw, choices):
    """``:subtasks`` and ``:ordering`` of a random partially ordered network."""
    n = draw(st.integers(1, 3))
    names = [draw(st.sampled_from(choices)) for _ in range(n)]
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]
    order = [p for p in pairs if draw(st.booleans())]
    text = ":subtasks (and " + " ".join(f"(s{i} ({x}))" for i, x in enumerate(names)) + ")"
    if order:
        text += " :ordering (and " + " ".join(f"(s{i} < s{j})" for i, j in order) + ")"
    return text


@st.composite
def problems(draw):
    """A domain and a problem: four actions on four facts, one to three
    compound tasks (task i decomposes into actions and tasks after it, so
    the space is finite), methods with and without a precondition."""
    out = [
        "(define (domain rnd)",
        "  (:requirements :hierarchy :negative-preconditions)",
        "  (:predicates " + " ".join(f"({f})" for f in FACTS) + ")",
    ]
    ntasks = draw(st.integers(1, 3))
    out += [f"  (:task t{i} :parameters ())" for i in range(ntasks)]
    for i in range(ntasks):
        for k in range(draw(st.integers(1, 2))):
            choices = [f"a{j}" for j in range(ACTIONS)] + [f"t{j}" for j in range(i + 1, ntasks)]
            pre = _conj([_literal(draw) for _ in range(draw(st.integers(0, 1)))])
            out.append(
                f"  (:method m{i}_{k} :parameters () :task (t{i}) :precondition {pre}"
                f" {_network(draw, choices)})"
            )
    for j in range(ACTIONS):
        pre = [_literal(draw) for _ in range(draw(st.integers(0, 2)))]
        adds = draw(st.sets(st.sampled_from(FACTS), max_size=2))
        dels = draw(st.sets(st.sampled_from([f for f in FACTS if f not in adds]), max_size=1))
        effect = _conj([f"({f})" for f in sorted(adds)] + [f"(not ({f}))" for f in sorted(dels)])
        out.append(f"  (:action a{j} :parameters () :precondition {_conj(pre)} :effect {effect})")
    out.append(")")
    init = draw(st.sets(st.sampled_from(FACTS)))
    goal = f"  (:goal {_literal(draw, negative=False)})" if draw(st.booleans()) else ""
    network = _network(draw, [f"t{i}" for i in range(ntasks)] + ["a0"])
    problem = [
        "(define (problem r1) (:domain rnd)",
        f"  (:htn :parameters () {network})",
        "  (:init " + " ".join(f"({f})" for f in sorted(init)) + ")",
        goal,
        ")",
    ]
    return "\n".join(out) + "\n", "\n".join(problem) + "\n"


def _first_plan(domain, instance, commit):
    search = BestFirst(domain, instance, commit=commit)
    return next((p for p in search.plans() if p is not None), None), search


def _check_plan(folder: Path, domain, problem, plan, search):
    text = ipc_text(plan, {})
    (verdict,) = [v for _p, v in verify_ipc_text(domain, problem, text, "plan.ipc")]
    assert verdict.valid, (text, verdict)
    if PANDA.is_file():
        ipc = folder / "plan.ipc"
        ipc.write_text(text)
        out = subprocess.run(
            [
                str(PANDA),
                "-C",
                "--verify",
                str(folder / "d.hddl"),
                str(folder / "p.hddl"),
                str(ipc),
            ],
            capture_output=True,
            text=True,
        )
        assert "Plan verification result: true" in out.stdout, text + out.stdout[-1500:]


def _solve_both(folder: Path, domain_text: str, problem_text: str):
    (folder / "d.hddl").write_text(domain_text)
    (folder / "p.hddl").write_text(problem_text)
    inputs = read_inputs(folder / "d.hddl", folder / "p.hddl", function_table(None))
    instance = inputs.problem.instances[0]
    with_rule, search = _first_plan(inputs.domain, instance, True)
    without, _ = _first_plan(inputs.domain, instance, False)
    return inputs, with_rule, without, search


def test_a_precondition_made_true_in_parallel(tmp_path):
    inputs, with_rule, without, search = _solve_both(tmp_path, LATER, LATER_PROBLEM)
    assert without is not None and with_rule is not None
    assert [s.name for s in with_rule.steps] == ["!prepare", "!finish"]
    _check_plan(tmp_path, inputs.domain, inputs.problem, with_rule, search)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_the_rule_loses_no_plan(case):
    domain_text, problem_text = case
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        inputs, with_rule, without, search = _solve_both(folder, domain_text, problem_text)
        assert (with_rule is None) == (without is None), domain_text + problem_text
        if with_rule is not None:
            _check_plan(folder, inputs.domain, inputs.problem, with_rule, search)
