"""Generated code agrees with the general engine, and can be debugged.

The compiled conjunctions (the code written per binding mode,
``htn.jshop.logic.modes``, and the generic nested-loop conjunction of
``htn.jshop.logic.compile``) must find the same satisfiers in the same order
as the general engine (``htn.jshop.logic.engine``): each conjunct asked of
the engine alone, left to right with backtracking. Hypothesis draws the
states, the bindings and the conjunctions (atoms with constants and
variables, negations, calls, assignments, axioms, fact axioms, flat list
arguments, atoms of another length).

Generated code is compiled under a name that says what it is, registered
with ``linecache`` (tracebacks show its lines), and ``HTN_DUMP_COMPILED``
writes it to files.
"""

from __future__ import annotations

import linecache
import os
import traceback
from contextlib import contextmanager

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import FunctionTable
from htn.jshop.logic import warming
from htn.jshop.logic.compile import NESTED_CONJUNCTS, _stacked_conjunction, conjunction
from htn.jshop.logic.engine import Logic
from htn.jshop.logic.state import State
from htn.jshop.readers.load import parse_text

from conftest import run_htn

CONSTANTS = ["a", "b", "c", "1", "2"]
VARS = [f"?v{i}" for i in range(5)]
AXIOMS = """
  (:- (s ?x) ((p ?x)) ((q ?x ?x)))
  (:- (t ?x ?y) ((q ?y ?x) (not (p ?x))))
  (:- (f a) nil) (:- (f b) nil) (:- (f a) nil)
"""

terms = st.sampled_from(CONSTANTS + VARS)
flat_list = st.lists(terms, min_size=0, max_size=2).map(lambda xs: "(on " + " ".join(xs) + ")")


def atom(draw) -> str:
    kind = draw(st.sampled_from(["p", "q", "r1", "r2", "f", "s", "t", "g"]))
    if kind in ("p", "f", "s"):
        return f"({kind} {draw(terms)})"
    if kind in ("q", "t"):
        return f"({kind} {draw(terms)} {draw(terms)})"
    if kind == "r1":  # r has atoms of two lengths in the state
        return f"(r {draw(terms)})"
    if kind == "r2":
        return f"(r {draw(terms)} {draw(terms)})"
    return f"(g {draw(flat_list)})"


@st.composite
def conjunct(draw) -> str:
    kind = draw(st.sampled_from(["atom", "atom", "atom", "not", "call", "assign", "list"]))
    if kind == "atom":
        return atom(draw)
    if kind == "not":
        return f"(not {atom(draw)})"
    if kind == "call":
        fn = draw(st.sampled_from(["=", "!="]))
        return f"(call {fn} {draw(terms)} {draw(terms)})"
    if kind == "assign":
        value = draw(st.sampled_from(["(call + 1 2)", "a", "(b c)", *VARS]))
        return f"(assign {draw(st.sampled_from(VARS))} {value})"
    return f"(call member {draw(terms)} ({draw(terms)} b))"


ground_atoms = (
    [f"(p {c})" for c in "abc"]
    + [f"(q {x} {y})" for x in "abc" for y in "abc"]
    + [f"(r {c})" for c in "ab"]
    + [f"(r {x} {y})" for x in "ab" for y in "abc"]
    + ["(f c)", "(g (on a b))", "(g (on a))", "(g (on b b))", "(g on)", "(g (on nil a))"]
)


@st.composite
def case(draw):
    items = draw(st.lists(conjunct(), min_size=1, max_size=7))
    head = draw(st.lists(st.sampled_from(VARS), unique=True, max_size=5))
    state = draw(st.lists(st.sampled_from(ground_atoms), unique=True, max_size=14))
    bound = draw(st.lists(st.sampled_from(CONSTANTS), min_size=len(head), max_size=len(head)))
    mask = draw(st.lists(st.booleans(), min_size=len(head), max_size=len(head)))
    return items, head, state, bound, mask


def reference(sats: list, env: list):
    """The general engine's satisfiers of each conjunct, left to right."""
    if not sats:
        yield env
        return
    for e in sats[0](env):
        yield from reference(sats[1:], e)


@contextmanager
def warm_after(calls: int):
    """Compile generated code after ``calls`` interpreted calls (the planner
    waits longer, see htn.jshop.logic.warming), so that a test sees both."""
    saved, warming.WARM = warming.WARM, calls
    try:
        yield
    finally:
        warming.WARM = saved


def outcome(sat, env: list):
    """The satisfiers in order, or the error raised on the way."""
    try:
        return [list(e) for e in sat(list(env))]
    except HtnError as exc:
        return ("error", exc.message)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(case())
def test_compiled_conjunctions_agree_with_the_general_engine(example):
    items, head, state_atoms, bound, mask = example
    text = f"(defdomain d ({AXIOMS} (:operator (!o {' '.join(head)}) ({' '.join(items)}) () ())))"
    domain = parse_text(text, "d.jshop", FunctionTable())
    op = domain.operators["!o"][0]
    problem = parse_text(f"(defproblem pr d ({' '.join(state_atoms)}) ())", "p.jshop")
    state = State()
    for a in problem.instances[0].state:
        state.add(a.pred, a.args)
    logic = Logic(domain, state, FunctionTable())
    env = [None] * op.nvars
    for var, value, on in zip(op.head.args, bound, mask):
        if on:
            env[var.index] = value
    expr = op.pre.expr
    conjuncts = expr.items if isinstance(expr, S.And) else [expr]
    general = [logic.expr(x) for x in conjuncts]
    expected = outcome(lambda e: reference(general, e), env)
    # the mode-compiled precondition: its first call of a mode takes the
    # general path, the next ones the code written for that mode
    with warm_after(2):
        compiled = logic.precondition(op.pre, op.head.args)
        for _ in range(3):
            assert outcome(compiled, env) == expected
        # the same conjunction with no known entry (any variable may be bound)
        anywhere = logic.expr(op.pre.expr)
        for _ in range(3):
            assert outcome(anywhere, env) == expected
    if len(general) > 1:
        assert outcome(conjunction(general), env) == expected
        assert outcome(_stacked_conjunction(general), env) == expected
    # on a frozen state (grounding's reachable facts) the code looks atoms up
    # by their bound arguments: the same satisfiers in the same order
    frozen = Logic(domain, state, FunctionTable())
    frozen.freeze()
    with warm_after(2):
        indexed = frozen.precondition(op.pre, op.head.args)
        anywhere = frozen.expr(op.pre.expr)
        for _ in range(3):
            assert outcome(indexed, env) == expected
            assert outcome(anywhere, env) == expected


def test_a_frozen_state_s_atoms_are_looked_up_by_their_bound_arguments():
    domain = parse_text(
        "(defdomain d ((:operator (!o ?x) ((q ?x ?y) (r ?y ?y ?z) (not (q ?z ?x))) () ())))",
        "d.jshop",
    )
    state = State()
    facts = [("q", ("a", "b")), ("q", ("a", "c")), ("q", ("b", "a")), ("r", ("c", "c", "a"))]
    facts += [("r", ("b", "b", "b")), ("r", ("b", "c", "a")), ("r", ("b",)), ("q", ("c", "a"))]
    for pred, args in facts:
        state.add(pred, args)
    op = domain.operators["!o"][0]
    answers = []
    for freeze in (False, True):
        logic = Logic(domain, state, FunctionTable())
        if freeze:
            logic.freeze()
        with warm_after(1):
            sat = logic.precondition(op.pre, op.head.args)
            runs = [[tuple(e) for e in sat(["a", None, None])] for _ in range(3)]
        assert runs[0] == runs[1] == runs[2]
        answers.append(runs[0])
        if freeze:  # the code asked the index, by the places its mode binds
            # ((not (q ?z ?x)) has both bound: a set lookup, as before)
            assert set(logic.indexes) == {("q", 2, (0,)), ("r", 3, (0, 1))}
            assert logic.indexes[("q", 2, (0,))]["a",] == [("a", "b"), ("a", "c")]
            assert logic.indexes[("r", 3, (0, 1))]["b", "b"] == [("b", "b", "b")]
        else:
            assert logic.indexes is None
    # (q a b): (r b b b), but (q b a) holds; (q a c): (r c c a), and (q a a) does not
    assert answers[0] == answers[1] == [("a", "c", "a")]


def test_long_conjunctions_backtrack_in_the_same_order():
    # past NESTED_CONJUNCTS, the conjunction runs on a stack of generators
    n = NESTED_CONJUNCTS + 3
    items = " ".join(f"(q ?v{i} ?v{i + 1})" for i in range(n))
    domain = parse_text(f"(defdomain d ((:operator (!o) ({items}) () ())))", "d.jshop")
    state = State()
    for x, y in [("a", "a"), ("a", "b"), ("b", "b")]:  # a...a b...b
        state.add("q", (x, y))
    logic = Logic(domain, state, FunctionTable())
    op = domain.operators["!o"][0]
    general = [logic.expr(x) for x in op.pre.expr.items]
    env = [None] * op.nvars
    expected = outcome(lambda e: reference(general, e), env)
    assert len(expected) == n + 2
    assert outcome(conjunction(general), env) == expected
    compiled = logic.precondition(op.pre, op.head.args)
    for _ in range(warming.WARM + 1):
        assert outcome(compiled, env) == expected


TRACED = """
import traceback
FRAMES = []

def look(x):
    FRAMES.extend(traceback.extract_stack())
    return x
"""


def test_generated_code_has_a_name_and_lines_in_tracebacks(tmp_path):
    functions = tmp_path / "fns.py"
    functions.write_text(TRACED)
    table = FunctionTable()
    table.load_file(str(functions))
    domain = parse_text(
        "(defdomain d (\n  (:operator (!go ?a)\n    ((at ?a) (call look ?a)) () ())))",
        str(tmp_path / "d.jshop"),
        table,
    )
    state = State()
    state.add("at", ("home",))
    logic = Logic(domain, state, table)
    op = domain.operators["!go"][0]
    sat = logic.precondition(op.pre, op.head.args, f"precondition of {op.name}")
    frames = table.user["look"].__globals__["FRAMES"]
    for _ in range(warming.WARM + 1):  # the last calls run the code written for the mode
        assert len(list(sat(["home"]))) == 1
    names = {f.filename: f for f in frames if f.filename.startswith("<htn: ")}
    mode = [n for n in names if n.startswith("<htn: precondition of !go, d.jshop:3")]
    assert mode, sorted(names)
    frame = names[mode[0]]
    assert "x0" in frame.line  # the generated line, from linecache
    assert linecache.getline(frame.filename, frame.lineno).strip() == frame.line
    shown = "".join(traceback.format_list([frame]))
    assert shown.startswith('  File "<htn: precondition of !go') and frame.line in shown


def test_dump_compiled_writes_each_piece(tmp_path):
    dump = tmp_path / "dump"
    d, p = tmp_path / "d.jshop", tmp_path / "p.jshop"
    d.write_text(
        "(defdomain d (\n  (:operator (!go ?a ?b) ((at ?a)) ((at ?a)) ((at ?b)))\n"
        "  (:method (travel ?to) ((at ?from)) ((!go ?from ?to)))))\n"
    )
    # often enough for the pieces to be compiled (htn.jshop.logic.warming)
    trips = " ".join(["(travel work) (travel home)"] * warming.WARM)
    p.write_text(f"(defproblem p d ((at home)) ({trips}))\n")
    r = run_htn("plan", d, p, env={**os.environ, "HTN_DUMP_COMPILED": str(dump)})
    assert r.returncode == 0, r.stderr
    files = sorted(f.name for f in dump.iterdir())
    assert any(f.startswith("precondition_of_go_d.jshop_2") for f in files), files
    assert any(f.startswith("subtasks_of_travel") for f in files), files
    text = next(f for f in dump.iterdir() if f.name.startswith("precondition_of_go")).read_text()
    compile(text, "dumped", "exec")  # each file is the Python it ran
    assert text.rstrip().splitlines()[-1].startswith("# <htn: precondition of !go, d.jshop:2")
