"""The reachable facts of grounding (:mod:`htn.jshop.search.reachability`):
the semi-naive fixpoint reaches exactly the facts of enumerating every
binding of every action at every turn, on IPC instances of both orders, and
leaving out the parameters that only a type condition reads (each added
atom taking every object of their types) reaches exactly the facts of
binding them."""

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


def _facts(domain, instance, semi_naive, factor=True):
    steps = reachable(domain, instance, semi_naive, factor)
    try:
        while True:
            next(steps)
    except StopIteration as done:
        state, _initial, _logic = done.value
    return {(pred, args) for pred, args in state.facts()}


@pytest.mark.corpus
@pytest.mark.parametrize("domain, problem", INSTANCES, ids=[p.split("/")[1] for _, p in INSTANCES])
def test_the_semi_naive_fixpoint_reaches_the_facts_of_the_naive_one(domain, problem):
    if not (CORPUS / domain).is_file():
        pytest.skip(f"{CORPUS / domain} not found")
    dom, prob = load_inputs(str(CORPUS / domain), str(CORPUS / problem))
    instance = prob.instances[0]
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
    if not (CORPUS / domain).is_file():
        pytest.skip(f"{CORPUS / domain} not found")
    dom, prob = load_inputs(str(CORPUS / domain), str(CORPUS / problem))
    instance = prob.instances[0]
    assert _facts(dom, instance, True) == _facts(dom, instance, True, factor=False)


def test_childsnacks_move_tray_leaves_its_destination_out():
    domain = CORPUS / "ipc2020-to" / "Childsnack" / "domain.hddl"
    if not domain.is_file():
        pytest.skip(f"{domain} not found")
    from htn.jshop.logic.engine import Logic
    from htn.jshop.logic.state import State
    from htn.jshop.search.reachability import _Program

    dom, _prob = load_inputs(str(domain), str(domain.parent / "p05.hddl"))
    (op,) = dom.operators["!move_tray"]
    program = _Program(op, Logic(dom, State()), every=False)
    # (at ?t ?p2): the tray goes anywhere; bound, it multiplied the bindings
    assert [op.head.args[i].name for i in program.types] == ["?p2"]
    assert _Program(op, Logic(dom, State()), every=False, factor=False).types == {}
