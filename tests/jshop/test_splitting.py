"""Parameter splitting before grounding (:mod:`htn.jshop.search.splitting`):
it splits what it should (IPC 2023 Snake's ``move-long-snake``) and leaves
what it must (a partially ordered problem, a subtask that is not the first,
a conjunct that reaches past the first subtask); the ground model shrinks;
on random totally ordered problems with parameters the grounded search
finds a plan exactly where it does without splitting, and every plan it
finds passes htn's decomposition check and pandaPIparser, with no task of
splitting's own in its tree."""

from __future__ import annotations

import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_commit_rule import _check_plan, _conj

from htn.api.inputs import function_table, read_inputs
from htn.jshop.language import syntax as S
from htn.jshop.search.best_first import BestFirst
from htn.jshop.search.grounding import ground
from htn.jshop.search.splitting import PREFIX, split_methods, totally_ordered

from conftest import SHARED

SNAKE = SHARED / "corpus" / "ipc2023-to" / "Snake"


def _read(folder: Path, domain: str, problem: str):
    (folder / "d.hddl").write_text(domain)
    (folder / "p.hddl").write_text(problem)
    inputs = read_inputs(folder / "d.hddl", folder / "p.hddl", function_table(None))
    return inputs, inputs.problem.instances[0]


def _names(m: S.Method) -> list:
    return [(x.name, [v.name for v in x.args]) for x in m.branches[0].tasks.items]


def test_snake_move_long_splits_into_the_body_cells_and_the_rest():
    inputs = read_inputs(
        SNAKE / "domain.hddl", SNAKE / "pb-3slots-seed1.snake.hddl", function_table(None)
    )
    methods, origin, made = split_methods(inputs.domain.methods)
    assert made == {"split:move-long-snake", "split:hunt_all"}
    (outer,) = [m for m in methods["move"] if m.branches[0].label == "move-long-snake"]
    assert origin[id(outer)].branches[0].label == "move-long-snake"
    assert _names(outer) == [
        ("split:move-long-snake", ["?snake", "?snakepos", "?pos2"]),
        ("move", ["?snake", "?pos2", "?goalpos"]),
    ]
    (inner,) = methods["split:move-long-snake"]
    assert _names(inner) == [
        ("!move-long", ["?snake", "?pos2", "?snakepos", "?bodypos", "?tailpos"])
    ]
    moved = {(c.pred, tuple(v.name for v in c.args)) for c in inner.branches[0].pre.expr.items}
    assert ("connected", ("?snake", "?bodypos", "?tailpos")) in moved
    assert ("tail", ("?snake", "?tailpos")) in moved
    left = outer.branches[0].pre.expr.items
    assert not any("?bodypos" in str(c) or "?tailpos" in str(c) for c in left)
    # move-short-snake has no variable only its first subtask reads: as written
    assert any(m.branches[0].label == "move-short-snake" for m in methods["move"])
    assert not [m for m in origin.values() if m.branches[0].label == "move-short-snake"]


def _snake_problem(width: int, height: int) -> str:
    """A small Snake problem: a two-cell snake in a corner, one mouse in the
    opposite one, no walls."""
    cells = [f"px{x}y{y}" for y in range(height) for x in range(width)]
    adjacent = []
    for y in range(height):
        for x in range(width):
            for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                if 0 <= x + dx < width and 0 <= y + dy < height:
                    adjacent.append(f"(adjacent px{x}y{y} px{x + dx}y{y + dy})")
    mouse = f"px{width - 1}y{height - 1}"
    return f"""(define (problem small) (:domain snake)
  (:objects viper - snake {" ".join(cells)} - location)
  (:init (head viper px1y0) (connected viper px1y0 px0y0) (tail viper px0y0)
    (occupied px0y0) (occupied px1y0) (occupied {mouse}) (mouse-at {mouse})
    {" ".join(adjacent)})
  (:htn :ordered-subtasks (and (hunt))))
"""


def test_the_ground_model_shrinks_and_the_plan_is_the_domain_as_written(tmp_path):
    inputs, instance = _read(tmp_path, (SNAKE / "domain.hddl").read_text(), _snake_problem(5, 4))
    split = ground(inputs.domain, instance)
    whole = ground(inputs.domain, instance, split=False)
    n_split = sum(len(ms) for ms in split.methods_of.values())
    n_whole = sum(len(ms) for ms in whole.methods_of.values())
    # about half here (one goal cell); the product grows with the goals:
    # 206k against more than 1.7 GB unfinished on the 4-slot IPC problem
    assert n_split * 3 < n_whole * 2, (n_split, n_whole)
    assert split.hidden == {"split:move-long-snake", "split:hunt_all"}
    assert any(name in split.hidden for name, _args in split.tasks)
    for heuristic in ("tdg", "rc"):
        search = BestFirst(inputs.domain, instance, heuristic=heuristic)
        plan = next(p for p in search.plans(timeout=60) if p is not None)
        names = []
        stack = [plan.tree]
        while stack:
            node = stack.pop()
            names.append(node.name)
            stack.extend(node.children)
        assert "move" in names and not any(n.startswith(PREFIX) for n in names)
        _check_plan(tmp_path, inputs.domain, inputs.problem, plan, search)


LEFT_ALONE = """(define (domain d) (:requirements :hierarchy :typing :method-preconditions)
  (:types o)
  (:predicates (p ?x - o) (q ?x ?y - o))
  (:task t :parameters (?x - o))
  (:method second :parameters (?x ?y - o) :task (t ?x)
    :precondition (q ?x ?y)
    :ordered-subtasks (and (a ?x) (b ?x ?y)))
  (:method reaches :parameters (?x ?y ?z - o) :task (t ?x)
    :precondition (and (q ?y ?z) (p ?z))
    :ordered-subtasks (and (b ?x ?y) (c ?z)))
  (:method split :parameters (?x ?y - o) :task (t ?x)
    :precondition (and (q ?x ?y) (p ?x))
    :ordered-subtasks (and (b ?x ?y) (a ?x)))
  (:action a :parameters (?x - o) :precondition () :effect (p ?x))
  (:action b :parameters (?x ?y - o) :precondition () :effect (q ?x ?y))
  (:action c :parameters (?x - o) :precondition () :effect ()))
"""


def test_only_a_first_subtasks_own_variables_with_their_own_conjuncts_move(tmp_path):
    problem = """(define (problem p) (:domain d) (:objects k l - o)
      (:htn :parameters () :ordered-subtasks (and (t k))) (:init (q k l)))"""
    inputs, instance = _read(tmp_path, LEFT_ALONE, problem)
    _methods, origin, made = split_methods(inputs.domain.methods)
    assert made == {"split:split"}
    assert [m.branches[0].label for m in origin.values()] == ["split"]
    assert totally_ordered(inputs.domain.methods, True)
    unordered = problem.replace(":ordered-subtasks (and (t k))", ":subtasks (and (t k) (t l))")
    inputs, instance = _read(tmp_path, LEFT_ALONE, unordered)
    model = ground(inputs.domain, instance)
    assert not model.hidden and not any(n.startswith(PREFIX) for n, _args in model.tasks)


LATER = """(define (domain d) (:requirements :hierarchy :typing :method-preconditions)
  (:types o)
  (:predicates (p ?x - o) (s ?x - o))
  (:task t :parameters (?x - o))
  (:method static :parameters (?x ?z - o) :task (t ?x)
    :precondition (s ?z) :ordered-subtasks (and (a ?x) (c ?z)))
  (:method changing :parameters (?x ?z - o) :task (t ?x)
    :precondition (p ?z) :ordered-subtasks (and (a ?x) (c ?z)))
  (:action a :parameters (?x - o) :precondition () :effect (p ?x))
  (:action c :parameters (?x - o) :precondition () :effect ()))
"""


def test_a_later_subtasks_own_variables_split_off_where_only_static_facts_read_them(
    tmp_path,
):
    # (s ?z) holds or not for the whole plan, so it may be tested when (c ?z)
    # is decomposed; (p ?z) may be made true by (a ?x) in between: it stays
    problem = """(define (problem p) (:domain d) (:objects k l - o)
      (:htn :parameters () :ordered-subtasks (and (t k))) (:init (s l)))"""
    inputs, instance = _read(tmp_path, LATER, problem)
    dynamic = inputs.domain.dynamic_predicates()
    assert split_methods(inputs.domain.methods)[2] == frozenset()  # first subtasks only
    methods, origin, made = split_methods(inputs.domain.methods, dynamic)
    assert made == {"split:static@2"}
    assert [m.branches[0].label for m in origin.values()] == ["static"]
    (inner,) = methods["split:static@2"]
    assert inner.head.args == () and _names(inner) == [("!c", ["?z"])]
    assert {c.pred for c in inner.branches[0].pre.expr.items} == {"s", "type:o"}
    (outer,) = [m for m in methods["t"] if m.branches[0].label == "static"]
    assert {c.pred for c in outer.branches[0].pre.expr.items} == {"type:o"}  # ?x's
    search = BestFirst(inputs.domain, instance)
    plan = next(p for p in search.plans(timeout=60) if p is not None)
    assert [(x.name, *x.args) for x in plan.steps] in (
        [("!a", "k"), ("!c", "l")],
        [("!a", "k"), ("!c", "k")],
    )
    _check_plan(tmp_path, inputs.domain, inputs.problem, plan, search)


# IPC 2020 Woodworking's `process` methods in small: the last subtask
# colours a part of its own, and the reader pulls that action's `(r ?z)`
# up into the method (no earlier subtask adds an r atom)
PULLED = """(define (domain d) (:requirements :hierarchy :typing :method-preconditions)
  (:types o)
  (:predicates (p ?x - o) (r ?x - o))
  (:task t :parameters (?x - o))
  (:method pulled :parameters (?x ?z - o) :task (t ?x)
    :ordered-subtasks (and (a ?x) (c ?z)))
  (:action a :parameters (?x - o) :precondition () :effect (p ?x))
  (:action c :parameters (?x - o) :precondition (r ?x) :effect (not (r ?x)))
  (:action d :parameters (?x - o) :precondition () :effect (r ?x)))
"""


def test_a_later_subtasks_condition_pulled_up_into_the_method_moves_back_with_it(tmp_path):
    # (r ?z) is dynamic, but the method holds it only because (c ?z) needs
    # it, and (a ?x) cannot add it: tested when (c ?z) comes, it decides the
    # same plans, and ?z no longer multiplies the method's instances
    problem = """(define (problem p) (:domain d) (:objects k l m - o)
      (:htn :parameters () :ordered-subtasks (and (t k))) (:init (r l)))"""
    inputs, instance = _read(tmp_path, PULLED, problem)
    (written,) = inputs.domain.methods["t"]
    assert [c.pred for c in written.branches[0].pre.pulled] == ["r"]
    methods, _origin, made = split_methods(
        inputs.domain.methods, inputs.domain.dynamic_predicates()
    )
    assert made == {"split:pulled@2"}
    (inner,) = methods["split:pulled@2"]
    assert "r" in {c.pred for c in inner.branches[0].pre.expr.items}
    (outer,) = methods["t"]
    assert "r" not in {c.pred for c in outer.branches[0].pre.expr.items}
    model = ground(inputs.domain, instance)
    assert len(model.methods_of[model.task_ids[("t", ("k",))]]) == 1  # not one per ?z
    search = BestFirst(inputs.domain, instance)
    plan = next(p for p in search.plans(timeout=60) if p is not None)
    assert [(x.name, *x.args) for x in plan.steps] == [("!a", "k"), ("!c", "l")]
    _check_plan(tmp_path, inputs.domain, inputs.problem, plan, search)


# IPC 2020 Minecraft-Player's find-way methods in small: `stop` walks the
# player from wherever it stands (?p, its only subtask's own variable) to
# ?x; `same` names no variable the head does not
ONE = """(define (domain d) (:requirements :hierarchy :typing :method-preconditions)
  (:types o)
  (:predicates (at ?x - o) (link ?x ?y - o))
  (:task go :parameters (?x ?y - o))
  (:method stop :parameters (?x ?y ?p - o) :task (go ?x ?y)
    :precondition (and (link ?x ?y) (at ?p)) :ordered-subtasks (and (walk ?p ?x)))
  (:method same :parameters (?x ?y ?n - o) :task (go ?x ?y)
    :precondition (link ?x ?n) :ordered-subtasks (and (go ?n ?y)))
  (:action walk :parameters (?p ?x - o) :precondition (at ?p)
    :effect (and (not (at ?p)) (at ?x))))
"""


def test_a_method_of_one_subtask_splits_where_the_head_names_more(tmp_path):
    problem = """(define (problem p) (:domain d) (:objects a b c - o)
      (:htn :parameters () :ordered-subtasks (and (go b c))) (:init (at a) (link b c)))"""
    inputs, instance = _read(tmp_path, ONE, problem)
    methods, origin, made = split_methods(inputs.domain.methods)
    # `stop`: the walk from ?p to ?x, once per ?x and not per (?x, ?y);
    # `same`: its new task would take ?x and ?y, as many as the method
    assert made == {"split:stop"}
    (inner,) = methods["split:stop"]
    assert [v.name for v in inner.head.args] == ["?x"]
    assert {c.pred for c in inner.branches[0].pre.expr.items} >= {"at"}
    search = BestFirst(inputs.domain, instance)
    plan = next(p for p in search.plans(timeout=60) if p is not None)
    assert [(x.name, *x.args) for x in plan.steps] == [("!walk", "a", "b")]
    assert [n.name for n in plan.tree.children[0].children] == ["!walk"]  # spliced out
    _check_plan(tmp_path, inputs.domain, inputs.problem, plan, search)


OBJECTS = ["k", "l", "m"]
PREDS = {"p": 1, "q": 2}


def _atom(draw, params: list, negative: bool = True) -> str:
    pred = draw(st.sampled_from(sorted(PREDS)))
    args = " ".join(draw(st.sampled_from(params)) for _ in range(PREDS[pred]))
    atom = f"({pred} {args})"
    return f"(not {atom})" if negative and draw(st.booleans()) else atom


def ordered_methods(draw, ntasks: int, actions: dict, extra: tuple, atom, most: int) -> list:
    """Lines of ``ntasks`` tasks of one parameter and their totally ordered
    methods: ``extra`` (least, most) more parameters each, up to ``most``
    literals ``atom(params)`` in the precondition, one to three subtasks
    among the actions (name -> arity) and the tasks after it."""
    out = [f"  (:task t{i} :parameters (?x - o))" for i in range(ntasks)]
    for i in range(ntasks):
        for k in range(draw(st.integers(1, 2))):
            params = ["?x"] + [f"?v{j}" for j in range(draw(st.integers(*extra)))]
            pre = _conj([atom(params) for _ in range(draw(st.integers(0, most)))])
            subtasks = []
            for s in range(draw(st.integers(1, 3))):
                name = draw(
                    st.sampled_from(sorted(actions) + [f"t{j}" for j in range(i + 1, ntasks)])
                )
                arity = actions.get(name, 1)
                args = " ".join(draw(st.sampled_from(params)) for _ in range(arity))
                subtasks.append(f"(s{s} ({name} {args}))")
            decl = " ".join(params) + " - o"
            out.append(
                f"  (:method m{i}_{k} :parameters ({decl}) :task (t{i} ?x)"
                f" :precondition {pre} :ordered-subtasks (and {' '.join(subtasks)}))"
            )
    return out


@st.composite
def problems(draw):
    """A totally ordered domain on three objects: actions of one or two
    parameters, tasks of one parameter whose methods have one to three
    more, in preconditions and subtasks (task i decomposes into actions
    and tasks after it, so the space is finite)."""
    out = [
        "(define (domain rnd)",
        "  (:requirements :hierarchy :typing :negative-preconditions :method-preconditions)",
        "  (:types o)",
        "  (:predicates (p ?a - o) (q ?a ?b - o))",
    ]
    ntasks = draw(st.integers(1, 3))
    actions = {"a0": 1, "a1": 2, "a2": 2}
    out += ordered_methods(draw, ntasks, actions, (1, 3), lambda ps: _atom(draw, ps), 3)
    for name, arity in actions.items():
        params = ["?y", "?z"][:arity]
        decl = " ".join(params) + " - o"
        pre = _conj([_atom(draw, params) for _ in range(draw(st.integers(0, 2)))])
        eff = _conj([_atom(draw, params) for _ in range(draw(st.integers(1, 2)))])
        out.append(f"  (:action {name} :parameters ({decl}) :precondition {pre} :effect {eff})")
    out.append(")")
    init = draw(st.sets(st.sampled_from([f"(p {o})" for o in OBJECTS] + ["(q k l)", "(q l m)"])))
    goal = f"  (:goal {_atom(draw, OBJECTS, negative=False)})" if draw(st.booleans()) else ""
    top = " ".join(
        f"(r{n} (t{draw(st.integers(0, ntasks - 1))} {draw(st.sampled_from(OBJECTS))}))"
        for n in range(draw(st.integers(1, 2)))
    )
    problem = [
        "(define (problem r1) (:domain rnd)",
        f"  (:objects {' '.join(OBJECTS)} - o)",
        f"  (:htn :parameters () :ordered-subtasks (and {top}))",
        f"  (:init {' '.join(sorted(init))})",
        goal,
        ")",
    ]
    return "\n".join(out) + "\n", "\n".join(problem) + "\n"


def _first(domain, instance, **options):
    search = BestFirst(domain, instance)
    search._prepared(ground(domain, instance, **options))
    return next((p for p in search.plans() if p is not None), None), search


def same_answer(case, option: str) -> None:
    """GBFS finds a plan of the random problem ``case`` with the grounding
    ``option`` on exactly where it finds one with it off, and both verifiers
    accept it."""
    domain_text, problem_text = case
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        inputs, instance = _read(folder, domain_text, problem_text)
        on, search = _first(inputs.domain, instance, **{option: True})
        off, _ = _first(inputs.domain, instance, **{option: False})
        assert (on is None) == (off is None), domain_text + problem_text
        if on is not None:
            _check_plan(folder, inputs.domain, inputs.problem, on, search)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_splitting_loses_no_plan_and_adds_none(case):
    same_answer(case, "split")


# JSHOP2 may give two methods the same label: each split gets a task of its
# own, or one method's new task could be decomposed by the other's half
REPEATED = """(defdomain d (
  (:operator (!a ?x) () () ((p ?x)))
  (:operator (!b ?x ?y) () () ((q ?x ?y)))
  (:method (t ?x) lbl ((r ?x ?y)) ((!b ?x ?y) (!a ?x)))
  (:method (u ?x) lbl ((r ?y ?x)) ((!b ?y ?x) (!a ?x)))
))
"""


def test_two_methods_of_one_label_get_a_task_each(tmp_path):
    (tmp_path / "d.jshop").write_text(REPEATED)
    (tmp_path / "p.jshop").write_text("(defproblem p d ((r k l) (r l k)) ((t k) (u k)))\n")
    inputs = read_inputs(tmp_path / "d.jshop", tmp_path / "p.jshop", function_table(None))
    _methods, _origin, made = split_methods(inputs.domain.methods)
    assert made == {"split:lbl", "split:lbl#2"}
    search = BestFirst(inputs.domain, inputs.problem.instances[0])
    plan = next(p for p in search.plans(timeout=60) if p is not None)
    steps = [(s.name, *s.args) for s in plan.steps]
    assert steps == [("!b", "k", "l"), ("!a", "k"), ("!b", "l", "k"), ("!a", "k")]
    assert [n.name for n in plan.tree.children] == ["t", "u"]
