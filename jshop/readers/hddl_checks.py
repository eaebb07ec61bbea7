"""What an HDDL domain must be before anything is derived from it.

The translation (:mod:`htn.jshop.readers.hddl_domain`) and the pull-up of
preconditions (:mod:`htn.jshop.readers.pullup`) index a task's declared
parameters by a subtask's arguments and walk the type hierarchy: both trust
the model. So the model is checked first, once, when it is read, and every
slip is an :class:`~htn.jshop.language.errors.HtnError` at its place:

* the type hierarchy has no cycle (``(:types ta - tb tb - ta)``) and names
  only declared types;
* a task declares each parameter once;
* a method decomposes a declared task with as many arguments as it takes;
  each subtask names a task or an action, with as many arguments as it
  takes; labels are unique, and ``:ordering`` names only labels, orders no
  subtask before itself and has no cycle.
"""

from __future__ import annotations

from htn.jshop.language.errors import HtnError

from .hddl_model import TOP, HDomain, MethodDef, Network
from .hddl_order import subtask_order


def type_ancestors(h: HDomain) -> dict:
    """Each type's supertypes (``object``, the root of every type, among them):
    ``type -> [supertype]``. An undeclared supertype, or a type that is its
    own supertype, is an error at the type's declaration."""
    types = dict(h.types)
    types.setdefault("object", [])
    where = getattr(h, "type_pos", {})
    out = {}
    for t in types:
        seen: list = []
        stack: list[tuple[str, tuple[str, ...]]] = [(s, (t, s)) for s in types[t]]
        while stack:
            s, path = stack.pop()
            if s not in types:
                raise HtnError.at(
                    where.get(t, h.pos), f"type {s} (a supertype of {t}) is not declared"
                )
            if s == t and t != "object":
                raise HtnError.at(
                    where.get(t, h.pos),
                    f"type {t} is its own supertype: "
                    f"{' - '.join(path)} (the type hierarchy must not have "
                    "a cycle)",
                )
            if s not in seen and s != t:
                seen.append(s)
                stack.extend((u, path + (u,)) for u in types[s])
        if t != "object" and "object" not in seen:
            seen.append("object")
        out[t] = seen
    return out


def check_domain(h: HDomain) -> dict:
    """Check the model (see the module docstring); the type ancestors."""
    ancestors = type_ancestors(h)
    for task in h.tasks.values():
        unique_params(task.params, f"task {task.name}")
    for m in h.methods:
        check_method(h, m)
    return ancestors


def unique_params(params, what: str) -> None:
    names: set = set()
    for p in params:
        if p.name in names:
            raise HtnError.at(p.pos, f"{what}: parameter {p.name} is declared twice")
        names.add(p.name)


def check_method(h: HDomain, m: MethodDef) -> None:
    """A method's task, subtasks and ordering fit the domain's declarations
    (the problem's root method too: its task is :data:`TOP`)."""
    if m.task.name != TOP:
        task = h.tasks.get(m.task.name)
        if task is None:
            kind = "an action" if m.task.name in h.actions else "not a declared task"
            raise HtnError.at(
                m.task.pos, f"method {m.name} decomposes {m.task.name}, which is {kind}"
            )
        _arity(m.task, len(task.params))
    owner = f"method {m.name}" if m.task.name != TOP else "the initial task network"
    check_network(h, m.network, owner, m.pos)


def check_network(h: HDomain, net: Network | None, owner: str, pos) -> None:
    """Each subtask is a task or an action of the domain with its arity;
    labels are unique and the ordering is a partial order over them."""
    if net is None:
        return
    for st in net.subtasks:
        if st.name in h.actions:
            _arity(st, len(h.actions[st.name].params))
        elif st.name in h.tasks:
            _arity(st, len(h.tasks[st.name].params))
        else:
            raise HtnError.at(
                st.pos, f"unknown task {st.name}: neither a task nor an action of the domain"
            )
    unique_labels(net, owner)
    subtask_order(net, owner, pos)  # unknown labels, self-orderings, cycles


def unique_labels(net: Network | None, owner: str) -> None:
    """No two subtasks of a network share a label."""
    labels: dict = {}
    for st in net.subtasks if net is not None else ():
        if st.label is not None:
            if st.label in labels:
                raise HtnError.at(
                    st.pos,
                    f"{owner}: label {st.label} is given to two "
                    f"subtasks (first at {labels[st.label].pos})",
                )
            labels[st.label] = st


def _arity(st, n: int) -> None:
    if n != len(st.args):
        raise HtnError.at(st.pos, f"{st.name} takes {n} argument(s), given {len(st.args)}")
