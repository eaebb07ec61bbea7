"""HDDL input: every instance of the IPC 2020 sample is parsed and planned
(depth-first; the first instance of each domain with every other search of
``htn plan --search`` too); each plan is checked three ways: its IPC decomposition against the domain
(as the competition's verifier does), ``htn validate`` (actions applicable
in order, goal true at the end), and a replay with ``htn run --robot
symbolic``. Errors in HDDL files are ``file:line:col`` with exit code 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from conftest import SHARED, run_htn

SAMPLE = SHARED / "corpus" / "ipc2020-to"


HEURISTIC_SEARCHES = ("gbfs", "wastar", "auto")


def _instances():
    """(domain, problem, search): every instance depth-first, and the first
    instance of each domain with every heuristic search (slow: Childsnack
    grounds for seconds)."""
    if not (SAMPLE / "README.md").is_file():
        return [
            pytest.param(
                None,
                None,
                "dfs",
                marks=pytest.mark.skip(reason=f"IPC sample not found at {SAMPLE}"),
            )
        ]
    out = []
    for folder in sorted(p for p in SAMPLE.iterdir() if p.is_dir()):
        problems = sorted(p for p in folder.glob("*.hddl") if p.name != "domain.hddl")
        for k, problem in enumerate(problems):
            name = f"{folder.name}-{problem.stem}"
            out.append(
                pytest.param(
                    folder / "domain.hddl",
                    problem,
                    "dfs",
                    id=f"{name}-dfs",
                    marks=pytest.mark.corpus,
                )
            )
            if k == 0:
                out += [
                    pytest.param(
                        folder / "domain.hddl",
                        problem,
                        search,
                        id=f"{name}-{search}",
                        marks=[pytest.mark.corpus, pytest.mark.slow],
                    )
                    for search in HEURISTIC_SEARCHES
                ]
    return out


def check_ipc_decomposition(
    text: str, domain: Path, problem: Path, steps: list, ordered: bool = True
) -> None:
    """What the IPC 2020 verifier checks of the decomposition: every line
    names a method of its task, the method's subtasks match the children under
    one binding of the method's variables, ids are used once, the root tasks
    are the problem's (in their order, with ``ordered``; an artificial
    ``__top`` root stands for them), and the actions are the plan's steps."""
    from htn.jshop.readers.hddl import parse_model
    from htn.jshop.readers.hddl_order import linearise

    dom, prob = parse_model(domain.read_text(), str(domain)), parse_model(problem.read_text())
    lines = text.splitlines()
    assert lines[0] == "==>" and lines[-1] == "<=="
    root = next(i for i, line in enumerate(lines) if line.startswith("root "))
    tasks = {}
    for line in lines[1:root]:
        ident, *atom = line.split()
        tasks[int(ident)] = tuple(a.lower() for a in atom)
    assert [tasks[i] for i in range(len(steps))] == steps
    methods = {m.name: m for m in dom.methods}
    decomposition = {}
    for line in lines[root + 1 : -1]:
        head, _, body = line.partition(" -> ")
        ident, *atom = head.split()
        method, *children = body.split()
        tasks[int(ident)] = tuple(a.lower() for a in atom)
        decomposition[int(ident)] = (method.lower(), [int(c) for c in children])
    used = [c for _, cs in decomposition.values() for c in cs]
    roots = [int(x) for x in lines[root].split()[1:]]
    assert sorted(used + roots) == sorted(tasks), "every task appears exactly once"
    initial = [(s.name, *s.args) for s in linearise(prob.network, "problem", None)]
    named = [tasks[r] for r in roots]
    if [t[0] for t in named] == ["__top"]:
        top = decomposition.pop(roots[0])
        assert top[0] == "__top_method"
        # its subtasks' arguments are the network's parameters: names compared only
        initial, named = [t[:1] for t in initial], [tasks[r][:1] for r in top[1]]
    if not ordered:  # a partial order: the same tasks, in an order it allows
        initial, named = sorted(initial), sorted(named)
    assert named == initial
    for ident, (mname, children) in decomposition.items():
        m = methods[mname]
        binding: dict = {}

        def match(pattern, values, binding=binding):
            assert len(pattern) == len(values)
            for p, v in zip(pattern, values):
                p = p.name if hasattr(p, "name") else p
                if p.startswith("?"):
                    assert binding.setdefault(p, v) == v
                else:
                    assert p == v

        assert m.task.name == tasks[ident][0]
        match(m.task.args, tasks[ident][1:])
        subtasks = linearise(m.network, mname, m.pos)
        assert len(subtasks) == len(children), line
        for st, child in zip(subtasks, children):
            assert tasks[child][0] == st.name
            match(st.args, tasks[child][1:])


@pytest.mark.parametrize("domain,problem,search", _instances())
def test_sample_instance_plans_validates_and_replays(tmp_path, ipc_oracle, domain, problem, search):
    plan_file = tmp_path / "plan.txt"
    result = run_htn(
        "plan",
        domain,
        problem,
        "-f",
        "ipc",
        "-o",
        plan_file,
        "--timeout",
        "120",
        "--search",
        search,
    )
    assert result.returncode == 0, result.stderr
    steps = [
        tuple(line.strip("()").replace("!", "", 1).split())
        for line in plan_file.read_text().splitlines()
        if line.startswith("(")
    ]
    assert steps
    check_ipc_decomposition(result.stdout, domain, problem, steps)
    (tmp_path / "plan.ipc").write_text(result.stdout)
    ipc_oracle.check(domain, problem, tmp_path / "plan.ipc")
    valid = run_htn("validate", domain, problem, plan_file)
    assert valid.returncode == 0, valid.stdout + valid.stderr
    assert f"valid, {len(steps)} steps" in valid.stdout
    replay = run_htn("run", plan_file, "--robot", "symbolic")
    assert replay.returncode == 0, replay.stdout + replay.stderr
    assert f"{len(steps)} of {len(steps)} steps verified" in replay.stdout + replay.stderr


DOMAIN = """(define (domain d)
  (:requirements :typing :hierarchy :negative-preconditions)
  (:types thing place - object)
  (:constants home - place)
  (:predicates (at ?t - thing ?p - place) (road ?a ?b - place))
  (:task move :parameters (?t - thing ?p - place))
  (:method m-move
    :parameters (?t - thing ?a ?p - place)
    :task (move ?t ?p)
    :precondition (and (at ?t ?a) (road ?a ?p))
    :ordered-subtasks (and (t1 (go ?t ?a ?p))))
  (:method m-stay
    :parameters (?t - thing ?p - place)
    :task (move ?t ?p)
    :precondition (at ?t ?p)
    :subtasks ())
  (:action go
    :parameters (?t - thing ?a ?b - place)
    :precondition (and (at ?t ?a) (not (at ?t ?b)))
    :effect (and (not (at ?t ?a)) (at ?t ?b))))
"""

PROBLEM = """(define (problem p) (:domain d)
  (:objects box - thing shop - place)
  (:htn :parameters () :subtasks (and (t1 (move box shop)) (t2 (move box home)))
        :ordering (and (< t1 t2)))
  (:init (at box home) (road home shop) (road shop home))
  (:goal (at box home)))
"""


def _write(tmp_path, domain=DOMAIN, problem=PROBLEM):
    (tmp_path / "d.hddl").write_text(domain)
    (tmp_path / "p.hddl").write_text(problem)
    return tmp_path / "d.hddl", tmp_path / "p.hddl"


def test_small_domain_every_format(tmp_path, ipc_oracle):
    d, p = _write(tmp_path)
    jshop = run_htn("plan", d, p, "-f", "jshop")
    assert jshop.returncode == 0, jshop.stderr
    assert jshop.stdout == (
        "Plan cost: 2.0\n\n(!go box home shop)\n(!go box shop home)\n--------------------\n"
    )
    ipc = run_htn("plan", d, p, "-f", "ipc")
    assert ipc.stdout == (
        "==>\n0 go box home shop\n1 go box shop home\nroot 2 3\n"
        "2 move box shop -> m-move 0\n3 move box home -> m-move 1\n<==\n"
    )
    (tmp_path / "plan.ipc").write_text(ipc.stdout)
    ipc_oracle.check(d, p, tmp_path / "plan.ipc")
    tree = run_htn("plan", d, p, "-f", "jshop", "--tree")
    assert "branch m-move" in tree.stdout and tree.stderr == ""  # piped: still stdout
    assert tree.stdout.startswith(jshop.stdout)
    as_json = run_htn("plan", d, p, "-f", "json")
    plan_line = json.loads(as_json.stdout.splitlines()[0])
    assert {n.get("branch") for n in plan_line["tree"]["nodes"]} >= {"m-move"}
    text = run_htn("plan", d, p, "-f", "text")
    assert "(!go box home shop)" in text.stdout


def test_goal_is_checked_on_the_final_state(tmp_path):
    d, p = _write(
        tmp_path, problem=PROBLEM.replace("(:goal (at box home))", "(:goal (at box shop))")
    )
    result = run_htn("plan", d, p, "-f", "jshop")
    assert result.returncode == 1 and result.stdout == ""
    plan = tmp_path / "plan.txt"
    plan.write_text(
        "Plan cost: 2.0\n\n(!go box home shop)\n(!go box shop home)\n--------------------\n"
    )
    result = run_htn("validate", d, p, plan)
    assert result.returncode == 1
    assert "the goal does not hold in the final state: (at box shop) is false" in result.stderr
    # a goal no action touches is found false only at the end: --explain says which atom
    d, p = _write(
        tmp_path,
        problem=PROBLEM.replace(
            "(:goal (at box home))", "(:goal (and (at box home) (road shop shop)))"
        ),
    )
    result = run_htn("plan", d, p, "-f", "jshop")
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert (
        f"goal ({p}:6:10): (road shop shop) does not hold in the final state "
        f"[{p}:6:29]" in result.stderr
    )


@pytest.mark.parametrize(
    "domain,problem,where,message",
    [
        (
            DOMAIN.replace("(at ?t ?a) (road ?a ?p))", "(at ?t ?a) (road ?a ?p)"),
            PROBLEM,
            "d.hddl:10:19",
            "this '(' is never closed; a ')' at the end of line 10 would close it",
        ),
        (
            DOMAIN.replace("(road ?a ?p))\n", "(raod ?a ?p))\n"),
            PROBLEM,
            "d.hddl:10:35",
            "unknown predicate raod",
        ),
        (
            DOMAIN.replace("(t1 (go ?t ?a ?p))", "(t1 (go ?t ?p))"),
            PROBLEM,
            "d.hddl:11:33",
            "go takes 3 argument(s), given 2",
        ),
        (
            DOMAIN.replace("(t1 (go ?t ?a ?p))", "(t1 (fly ?t ?p))"),
            PROBLEM,
            "d.hddl:11:33",
            "unknown task fly",
        ),
        (
            DOMAIN.replace("?a ?p - place)\n    :task", "?a ?p - plac)\n    :task"),
            PROBLEM,
            "d.hddl:8:37",
            "unknown type plac",
        ),
        (
            DOMAIN,
            PROBLEM.replace("(< t1 t2)", "(< t1 t2) (< t2 t1)"),
            "p.hddl:3:",
            "the ordering constraints form a cycle",
        ),
        (
            DOMAIN,
            PROBLEM.replace("(< t1 t2)", "(< t1 t3)"),
            "p.hddl:4:25",
            "no subtask is labelled t3",
        ),
        (
            DOMAIN,
            PROBLEM.replace("(:init", "(:int"),
            "p.hddl:5:4",
            "unknown keyword ':int'; did you mean :init?",
        ),
        # a goal or an initial state the domain cannot speak of: an error where
        # it is written, not a search to the time limit
        (
            DOMAIN,
            PROBLEM.replace("(:goal (at box home))", "(:goal (and (at box home) (atx box)))"),
            "p.hddl:6:29",
            "unknown predicate atx in the goal (the domain declares no such predicate)",
        ),
        (
            DOMAIN,
            PROBLEM.replace("(:goal (at box home))", "(:goal (not (at box)))"),
            "p.hddl:6:15",
            "predicate at takes 2 argument(s), given 1 in the goal",
        ),
        (
            DOMAIN,
            PROBLEM.replace("(:goal (at box home))", "(:goal (at box garage))"),
            "p.hddl:6:10",
            "unknown object garage in the goal (neither an object of the problem "
            "nor a constant of the domain)",
        ),
        (
            DOMAIN,
            PROBLEM.replace("(road shop home))", "(road shop home) (road shop mall))"),
            "p.hddl:5:58",
            "unknown object mall in the initial state",
        ),
        (
            DOMAIN,
            PROBLEM.replace("(road shop home))", "(raod shop home))"),
            "p.hddl:5:41",
            "unknown predicate raod in the initial state",
        ),
    ],
)
def test_hddl_errors_name_file_line_col(tmp_path, domain, problem, where, message):
    d, p = _write(tmp_path, domain, problem)
    result = run_htn("plan", d, p)
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    first = result.stderr.splitlines()[0]
    assert first.startswith(str(tmp_path / where)), first
    assert message in first


FORMULAS = """(define (domain lights)
  (:requirements :typing :hierarchy :negative-preconditions :conditional-effects
                 :universal-preconditions :existential-preconditions :equality)
  (:types lamp switch - device room)
  (:constants hall - room)
  (:predicates (on ?d - device) (in ?d - device ?r - room) (broken ?l - lamp) (lit ?r - room)
               (wired ?s - switch ?l - lamp))
  (:task light :parameters (?r - room))
  (:task press :parameters (?s - switch))
  (:task toggle-all :parameters ())
  (:method m-light-done :parameters (?r - room) :task (light ?r)
    :precondition (exists (?l - lamp) (and (in ?l ?r) (on ?l)))
    :subtasks ())
  (:method m-light :parameters (?r - room ?s - switch) :task (light ?r)
    :precondition (and (in ?s ?r) (forall (?l - lamp) (imply (wired ?s ?l) (not (broken ?l)))))
    :ordered-subtasks (and (t1 (press ?s)) (t2 (check ?r))))
  (:method m-press :parameters (?s - switch) :task (press ?s) :subtasks (and (flip ?s)))
  (:method m-toggle :parameters () :task (toggle-all) :subtasks (toggle))
  (:action flip :parameters (?s - switch)
    :precondition (not (on ?s))
    :effect (and (on ?s) (forall (?l - lamp) (when (wired ?s ?l) (and (on ?l) (not (broken ?l)))))))
  (:action check :parameters (?r - (either room))
    :precondition (or (= ?r hall) (exists (?l - lamp) (and (in ?l ?r) (on ?l))))
    :effect (lit ?r))
  (:action toggle :parameters ()
    :effect (forall (?l - lamp) (and (when (on ?l) (not (on ?l))) (when (not (on ?l)) (on ?l))))))
"""


@pytest.mark.parametrize(
    "tasks,state,goal,steps",
    [
        # exists and forall/imply in method preconditions, either types, = with a
        # constant, a conditional effect under forall, a quantified goal
        (
            "(light kitchen)",
            "",
            "(and (lit kitchen) (forall (?l - lamp) (imply (in ?l kitchen) (on ?l))))",
            ["(!flip s2)", "(!check kitchen)"],
        ),
        # conditions are evaluated before the action (PDDL), so toggle swaps l1 and l2
        ("(toggle-all)", "(on l1)", "(and (on l2) (not (on l1)))", ["(!toggle)"]),
    ],
)
def test_formulas_and_conditional_effects(tmp_path, tasks, state, goal, steps):
    problem = f"""(define (problem p) (:domain lights)
      (:objects l1 l2 - lamp s1 s2 - switch kitchen - room)
      (:htn :ordered-subtasks (and {tasks}))
      (:init (in l1 kitchen) (in s1 kitchen) (in s2 kitchen) (wired s1 l2) (wired s2 l1)
             (broken l2) {state})
      (:goal {goal}))"""
    d, p = _write(tmp_path, FORMULAS, problem)
    plan = tmp_path / "plan.txt"
    result = run_htn("plan", d, p, "-f", "jshop", "-o", plan)
    assert result.returncode == 0, result.stderr
    assert [line for line in result.stdout.splitlines() if line.startswith("(")] == steps
    assert run_htn("validate", d, p, plan).returncode == 0
