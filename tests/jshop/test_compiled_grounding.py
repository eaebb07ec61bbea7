"""Grounding's compiled formulas and method bodies
(:mod:`htn.jshop.search.residual_code`) and the heuristic's resumable
h_add passes (:mod:`htn.jshop.search.heuristics`) give what the general
walk and a complete pass give, on IPC instances."""

from __future__ import annotations

import hashlib

import pytest

from htn.jshop.readers.load import load_inputs
from htn.jshop.search import ground_formulas, grounding
from htn.jshop.search.best_first import BestFirst
from htn.jshop.search.ground_formulas import bits
from htn.jshop.search.heuristics import INF
from htn.jshop.search.task_networks import tasks

from conftest import SHARED

CORPUS = SHARED / "corpus"
INSTANCES = [  # forall, or, not, equality, conditional effects, partial order
    ("ipc2020-to/Childsnack/domain.hddl", "ipc2020-to/Childsnack/p05.hddl"),
    ("ipc-po/UM-Translog/domain.hddl", "ipc-po/UM-Translog/06-A-AutoTruck.hddl"),
    ("ipc-po/Rover/domain.hddl", "ipc-po/Rover/pfile01.hddl"),
    ("ipc-po/Barman-BDI/domain.hddl", "ipc-po/Barman-BDI/pfile02.hddl"),
    (
        "ipc2020-to-hard/Entertainment/pfile11-domain.hddl",
        "ipc2020-to-hard/Entertainment/pfile11.hddl",
    ),
]
IDS = [p.split("/")[1] for _, p in INSTANCES]


def _inputs(domain, problem):
    if not (CORPUS / domain).is_file():
        pytest.skip(f"{CORPUS / domain} not found")
    dom, prob = load_inputs(str(CORPUS / domain), str(CORPUS / problem))
    return dom, prob.instances[0]


def _fingerprint(model) -> str:
    h = hashlib.sha1()
    h.update(repr((model.facts, model.tasks, model.init, model.roots, model.goal)).encode())
    for t in sorted(model.methods_of):
        h.update(repr([(gm.method.name, gm.pre, gm.body) for gm in model.methods_of[t]]).encode())
    for t in sorted(model.actions):
        a = model.actions[t]
        h.update(repr((t, a.pre, a.dels, a.adds, a.effects, a.cost)).encode())
    return h.hexdigest()


@pytest.mark.corpus
@pytest.mark.parametrize("domain, problem", INSTANCES, ids=IDS)
def test_compiled_residuals_and_bodies_ground_the_model_of_the_walk(domain, problem, monkeypatch):
    dom, instance = _inputs(domain, problem)
    models = {}
    calls = {}
    for after in (10**9, 1):  # never compiled; compiled at once
        monkeypatch.setattr(ground_formulas, "COMPILE_AFTER", after)
        monkeypatch.setattr(grounding, "COMPILE_AFTER", after)
        walked = []
        walk = ground_formulas.FormulaGrounder.walk

        def counting(self, e, env, _walk=walk, _seen=walked):
            _seen.append(1)
            return _walk(self, e, env)

        monkeypatch.setattr(ground_formulas.FormulaGrounder, "walk", counting)
        models[after] = grounding.ground(dom, instance)
        calls[after] = len(walked)
        monkeypatch.setattr(ground_formulas.FormulaGrounder, "walk", walk)
    assert calls[1] < calls[10**9]  # the compiled code ran in place of walks
    assert _fingerprint(models[1]) == _fingerprint(models[10**9])
    assert models[1].methods_of and models[1].actions


@pytest.mark.corpus
@pytest.mark.parametrize(
    "domain, problem",
    [pytest.param(*INSTANCES[0], id=IDS[0], marks=pytest.mark.slow), *INSTANCES[1:3]],
    ids=IDS[:3],
)
def test_resumed_h_add_passes_give_the_costs_of_complete_ones(domain, problem):
    dom, instance = _inputs(domain, problem)
    search = BestFirst(dom, instance)
    search.prepare()
    h, checked = search.h, []
    relaxation = h.relaxation

    def checking(state, net):
        value = h(state, net)
        if len(checked) >= 300:
            return value
        full = relaxation.costs(bits(state))
        need = h.goal + [relaxation.nfacts + t for t in tasks(net)]
        costs = [full[n] for n in need]
        assert value == (INF if None in costs else sum(costs))
        checked.append(value)
        return value

    search.h = checking
    for plan in search.plans():
        if plan is not None or len(checked) >= 300:
            break
    assert len(checked) > 10
    assert len(h._passes) and any(not p.done for p in h._passes.values())  # some stopped early
