"""The reachable facts of grounding (:mod:`htn.jshop.search.reachability`):
the semi-naive fixpoint reaches exactly the facts of enumerating every
binding of every action at every turn, on IPC instances of both orders, and
leaving out the parameters that only a type condition reads (each added
atom taking every object of their types) reaches exactly the facts of
binding them, and so does adding the facts of bindings that agree on the
parameters the added atoms read only once."""

from __future__ import annotations

import pytest

from htn.jshop.readers.load import load_inputs
from htn.jshop.search.reachability import reachable

from conftest import SHARED

CORPUS = SHARED / "corpus"
INSTANCES = [  # (domain, problem) under the corpus: conditional effects, types, many actions
    ("ipc2020-to/Childsnack/domain.hddl", "ipc2020-to/Childsnack/p05.hddl"),
    ("ipc-po/Rover/domain.hddl", "ipc-po/Rover/pfile01.hddl"),
    ("ipc-po/UM-Translog/domain.hddl", "ipc-po/UM-Translog/06-A-AutoTruck.hddl"),
    (
        "ipc2020-to-hard/Multiarm-Blocksworld/domain.hddl",
        "ipc2020-to-hard/Multiarm-Blocksworld/pfile_02_055.hddl",
    ),
    (
        "ipc2020-to-hard/Monroe-Partially-Observable/pfile14-p-0017-clear-road-tree-13-domain.hddl",
        "ipc2020-to-hard/Monroe-Partially-Observable/pfile14-p-0017-clear-road-tree-13.hddl",
    ),
]


def _facts(domain, instance, semi_naive, factor=True, once=True):
    steps = reachable(domain, instance, semi_naive, factor, once)
    try:
        while True:
            next(steps)
    except StopIteration as done:
        state, _initial, _logic = done.value
    return {(pred, args) for pred, args in state.facts()}


def _load(domain: str, problem: str):
    """The domain and the problem's instance, from the corpus (skipped without it)."""
    if not (CORPUS / domain).is_file():
        pytest.skip(f"{CORPUS / domain} not found")
    dom, prob = load_inputs(str(CORPUS / domain), str(CORPUS / problem))
    return dom, prob.instances[0]


@pytest.mark.corpus
@pytest.mark.parametrize("domain, problem", INSTANCES, ids=[p.split("/")[1] for _, p in INSTANCES])
def test_the_semi_naive_fixpoint_reaches_the_facts_of_the_naive_one(domain, problem):
    dom, instance = _load(domain, problem)
    fast = _facts(dom, instance, True)
    assert fast == _facts(dom, instance, False)
    assert len(fast) > len(instance.state)  # the actions added some


FACTORED = [  # Ultralight-Cockpit: 19 actions with a parameter only their effects name
    *INSTANCES,
    ("ipc-po/Ultralight-Cockpit/UL_domain.hddl", "ipc-po/Ultralight-Cockpit/pfile02.hddl"),
]


@pytest.mark.corpus
@pytest.mark.parametrize("domain, problem", FACTORED, ids=[p.split("/")[1] for _, p in FACTORED])
def test_leaving_out_only_typed_parameters_reaches_the_same_facts(domain, problem):
    dom, instance = _load(domain, problem)
    assert _facts(dom, instance, True) == _facts(dom, instance, True, factor=False)


ONCE = [  # Woodworking: grinding reads a part's surface, colour and treatment, adds new ones
    *FACTORED,
    ("ipc-po/Woodworking/domain.hddl", "ipc-po/Woodworking/04--p02-part3.hddl"),
]


@pytest.mark.corpus
@pytest.mark.parametrize("domain, problem", ONCE, ids=[p.split("/")[1] for _, p in ONCE])
def test_bindings_that_add_the_same_atoms_are_added_once(domain, problem):
    dom, instance = _load(domain, problem)
    assert _facts(dom, instance, True) == _facts(dom, instance, True, once=False)


def _program(domain: str, problem: str, action: str, **options):
    """The reachability program of ``action`` (a corpus domain's only
    operator of that name), and the operator."""
    path = CORPUS / domain
    if not path.is_file():
        pytest.skip(f"{path} not found")
    from htn.jshop.logic.engine import Logic
    from htn.jshop.logic.state import State
    from htn.jshop.search.reachability import _Program

    dom, _prob = load_inputs(str(path), str(path.parent / problem))
    (op,) = dom.operators[action]
    return op, _Program(op, Logic(dom, State()), every=False, **options)


def test_the_key_of_grinding_leaves_out_what_it_only_reads():
    op, program = _program("ipc-po/Woodworking/domain.hddl", "01--p01-complete.hddl", "!do_grind")
    assert program.key is not None
    names = [a.name for a in op.head.args]
    left_out = set(names) - {names[i] for i in [*program.key, *program.types]}
    assert left_out == {"?do_grind_oldsurface", "?do_grind_oldcolour", "?do_grind_oldtreatment"}


def test_childsnacks_move_tray_leaves_its_destination_out():
    op, program = _program("ipc2020-to/Childsnack/domain.hddl", "p05.hddl", "!move_tray")
    # (at ?t ?p2): the tray goes anywhere; bound, it multiplied the bindings
    assert [op.head.args[i].name for i in program.types] == ["?p2"]
    _op, bound = _program(
        "ipc2020-to/Childsnack/domain.hddl", "p05.hddl", "!move_tray", factor=False
    )
    assert bound.types == {}
