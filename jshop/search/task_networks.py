"""Task networks of the progression search, as immutable values.

HDDL's ordering is inherited: when a task is decomposed, every subtask
takes over the task's ordering constraints (Höller et al., AAAI 2020), so
a network is always a tree of partially ordered groups. Here:

* a *sequence* is a tuple of items in total order: only its first item may
  start; an item is a task id (an ``int``) or a *group*;
* a *group* ``(members, preds)`` is a partial order of sequences:
  ``preds[i]`` is the bit mask of the members that must finish before
  member ``i`` starts. A finished member is removed (and the masks renumbered),
  a group of one member is spliced into its sequence.

Progression (Höller et al., "HTN Planning as Heuristic Progression Search",
JAIR 2020): the tasks that may be done next are the first items reached
through members whose mask is empty (:func:`firsts`, each with the path of
member indices that leads to it); doing one replaces it by a method's
body, or by nothing when it is an action (:func:`replace`). Equal networks
are equal tuples, so ``(state, network)`` is a key for duplicate detection.
"""

from __future__ import annotations

from htn.jshop.language.syntax import PartialOrder


def body_items(body: tuple, order) -> tuple:
    """The items a method body puts in place of its task."""
    if order is True or len(body) <= 1:
        return body
    members = tuple((t,) for t in body)
    if order is False:
        return ((members, (0,) * len(body)),)
    assert type(order) is PartialOrder
    return ((members, tuple(sum(1 << j for j in preds) for preds in order)),)


def firsts(seq: tuple, path: tuple = ()) -> list:
    """``(path, task)`` for every task that may be done next."""
    out: list = []
    stack = [(seq, path)]
    while stack:
        seq, path = stack.pop()
        if not seq:
            continue
        head = seq[0]
        if type(head) is int:
            out.append((path, head))
            continue
        members, preds = head
        for i in range(len(members) - 1, -1, -1):
            if not preds[i]:
                stack.append((members[i], path + (i,)))
    return out


def replace(seq: tuple, path: tuple, new: tuple, k: int = 0) -> tuple:
    """The network with the task at ``path`` replaced by the items ``new``."""
    head = seq[0]
    if type(head) is int:
        return new + seq[1:] if new else seq[1:]
    members, preds = head
    i = path[k]
    member = replace(members[i], path, new, k + 1)
    if member:
        members = members[:i] + (member,) + members[i + 1 :]
    else:
        members = members[:i] + members[i + 1 :]
        low = (1 << i) - 1
        preds = tuple((m & low) | ((m >> (i + 1)) << i) for j, m in enumerate(preds) if j != i)
    if not members:
        return seq[1:]
    if len(members) == 1:
        return members[0] + seq[1:]
    return ((members, preds),) + seq[1:]


def serialize(seq: tuple, path: tuple, k: int = 0) -> tuple:
    """``(network, path)``: the network with the member that ``path`` enters
    in each group on its way taken out in front of the group's other
    members (finished before any of them starts), and the task's path in
    it (``()``: the task is first). See ``BestFirst``'s ``serial``."""
    head = seq[0]
    if type(head) is int:
        return seq, ()
    members, preds = head
    i = path[k]
    inner, _ = serialize(members[i], path, k + 1)
    others = members[:i] + members[i + 1 :]
    low = (1 << i) - 1
    rest = tuple((m & low) | ((m >> (i + 1)) << i) for j, m in enumerate(preds) if j != i)
    tail = others[0] if len(others) == 1 else ((others, rest),)
    return inner + tail + seq[1:], ()


def tasks(seq: tuple):
    """Every task id of the network (with repetitions)."""
    stack = [seq]
    while stack:
        for x in stack.pop():
            if type(x) is int:
                yield x
            else:
                stack.extend(x[0])


def item_at(seq: tuple, path: tuple) -> int:
    """The task at ``path`` (as :func:`firsts` gives it)."""
    k = 0
    while True:
        head = seq[0]
        if type(head) is int:
            return head
        seq = head[0][path[k]]
        k += 1
