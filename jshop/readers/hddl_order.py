"""The order of a task network's subtasks (HDDL ``:ordered-subtasks``,
``:subtasks`` with or without ``:ordering``; Höller et al., AAAI 2020).

HDDL's ordering is a partial order: a subtask may start when every subtask
ordered before it is finished, and subtasks with no constraint between them
interleave. :func:`subtask_order` gives the subtasks in a topological order
(ties in written order) and says how they are ordered:

* ``:ordered-subtasks``, a single subtask, or an ``:ordering`` that orders
  every pair (a chain): a total order, the list runs in order;
* ``:subtasks`` with no ``:ordering`` (or an empty one) and several subtasks:
  no pair is ordered, the list is unordered (JSHOP2's ``:unordered``);
* any other ``:ordering``: a :class:`~htn.jshop.language.syntax.PartialOrder`
  over the sorted subtasks (each one's direct predecessors).
"""

from __future__ import annotations

from htn.jshop.language.errors import HtnError
from htn.jshop.language.syntax import PartialOrder

from .hddl_model import Network


def subtask_order(net: Network | None, owner: str, pos) -> tuple[list, object]:
    """``(subtasks, order)``: the subtasks in a topological order and
    ``True`` (total order), ``False`` (no two ordered) or a
    :class:`PartialOrder` (see the module docstring)."""
    if net is None:
        return [], True
    subs = net.subtasks
    if net.ordered or len(subs) <= 1:
        return list(subs), True
    if not net.ordering:
        return list(subs), False
    labels = {}
    for s in subs:
        if s.label is None:
            raise HtnError.at(
                s.pos,
                f"{owner}: a subtask needs a label to be ordered (or write :ordered-subtasks)",
            )
        labels[s.label] = s
    written = {label: i for i, label in enumerate(labels)}
    after: dict = {label: set() for label in labels}
    preds: dict = {label: set() for label in labels}
    for a, b, opos in net.ordering:
        for x in (a, b):
            if x not in labels:
                raise HtnError.at(opos, f"{owner}: no subtask is labelled {x}")
        if a == b:
            raise HtnError.at(opos, f"{owner}: subtask {a} is ordered before itself")
        after[a].add(b)
        preds[b].add(a)
    order, total = _topological(labels, after, preds, written)
    if len(order) != len(labels):
        raise HtnError.at(net.pos or pos, f"{owner}: the ordering constraints form a cycle")
    tasks = [labels[label] for label in order]
    if total:
        return tasks, True
    index = {label: i for i, label in enumerate(order)}
    return tasks, PartialOrder(tuple(sorted(index[p] for p in preds[label])) for label in order)


def _topological(labels: dict, after: dict, preds: dict, written: dict) -> tuple[list, bool]:
    """Kahn's algorithm, ready subtasks taken in written order; the order is
    total when exactly one subtask is ready at every step."""
    count = {label: len(preds[label]) for label in labels}
    ready = sorted((label for label in labels if count[label] == 0), key=written.__getitem__)
    order, total = [], True
    while ready:
        if len(ready) > 1:
            total = False
        label = ready.pop(0)
        order.append(label)
        for b in after[label]:
            count[b] -= 1
            if count[b] == 0:
                ready.append(b)
        ready.sort(key=written.__getitem__)
    return order, total


def linearise(net: Network | None, owner: str, pos) -> list:
    """The subtasks of a network in a topological order (one linearisation)."""
    return subtask_order(net, owner, pos)[0]


def is_total(net: Network | None) -> bool:
    """Whether a network's subtasks are totally ordered (see :func:`subtask_order`);
    the caller reports malformed orderings where it reads them."""
    try:
        return subtask_order(net, "", None)[1] is True
    except HtnError:
        return True
