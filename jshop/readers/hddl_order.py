"""The order of a task network's subtasks (HDDL ``:ordered-subtasks``,
``:subtasks`` with ``:ordering``).

This is a total-order planner: an ``:ordering`` must order every pair of
subtasks; ``:subtasks`` with no ``:ordering`` at all are taken in the written
order (one linearisation of the empty partial order, as HyperTensioN and the
other IPC 2020 total-order planners take them).
"""
from __future__ import annotations

from typing import Optional

from htn.jshop.language.errors import HtnError

from .hddl_model import Network


def linearise(net: Optional[Network], owner: str, pos) -> list:
    """The subtasks of a network in its total order (see the module docstring)."""
    if net is None:
        return []
    subs = net.subtasks
    if net.ordered or len(subs) <= 1 or not net.ordering:
        # no ordering constraint at all: the written order, one linearisation
        # of the (empty) partial order, as HyperTensioN and the other IPC 2020
        # total-order planners take it (Minecraft's place-block-abstract-3)
        return list(subs)
    labels = {}
    for s in subs:
        if s.label is None:
            raise HtnError.at(s.pos, f"{owner}: an unordered subtask needs a label to be "
                              "ordered (or write :ordered-subtasks)")
        labels[s.label] = s
    after: dict = {label: set() for label in labels}
    before_count = dict.fromkeys(labels, 0)
    for a, b, opos in net.ordering:
        for x in (a, b):
            if x not in labels:
                raise HtnError.at(opos, f"{owner}: no subtask is labelled {x}")
        if b not in after[a]:
            after[a].add(b)
            before_count[b] += 1
    order = []
    ready = [label for label in labels if before_count[label] == 0]
    while ready:
        if len(ready) > 1:
            raise HtnError.at(net.pos or pos, f"{owner}: subtasks {ready[0]} and {ready[1]} "
                              "are not ordered; the planner needs a total order")
        label = ready.pop()
        order.append(labels[label])
        for b in sorted(after[label], key=list(labels).index):
            before_count[b] -= 1
            if before_count[b] == 0:
                ready.append(b)
    if len(order) != len(labels):
        raise HtnError.at(net.pos or pos, f"{owner}: the ordering constraints form a cycle")
    return order
