"""Plans in the IPC 2020 HTN format, which the competition's verifier reads.

The format (pandaPIparser's ``-verify``; the IPC 2020 rules)::

    ==>
    0 drive truck_0 city_loc_2 city_loc_1
    1 pick_up truck_0 city_loc_1 package_0 capacity_0 capacity_1
    root 3 5
    3 deliver package_0 city_loc_0 -> m_deliver_ordering_0 4 1 ...
    4 get_to truck_0 city_loc_1 -> m_drive_to_ordering_0 0
    <==

First the primitive plan, one action per line in execution order: an id, the
action's name and its arguments. Then ``root`` with the ids of the initial
task network's tasks, and one line per decomposition: the id of a compound
task, the task with its arguments, ``->``, the method's name and the ids of
the subtasks it produced in the method's order. Ids are unique across actions
and tasks (actions take 0..n-1, compound tasks the ids after). Names are
printed as the HDDL files spell them (the verifier compares names exactly).
Needs the plan's task tree (the planner records it with ``record_trees``).
"""
from __future__ import annotations

from htn.jshop.language.terms import term_str


def ipc_text(plan, spelling: dict) -> str:
    """The plan (with its ``tree``) as IPC 2020 text, ``==>`` to ``<==``."""
    def spell(name: str) -> str:
        name = name.lstrip("!")
        return spelling.get(name, name)

    def line(name: str, args) -> str:
        return " ".join([spell(name), *(spell(term_str(a)) for a in args)])

    out = ["==>"]
    out += [f"{i} {line(s.name, s.args)}" for i, s in enumerate(plan.steps)]
    tree = plan.tree
    ids: dict = {}
    next_id = len(plan.steps)
    nodes = [n for n in tree.walk() if n is not tree]
    for node in nodes:
        if node.step is not None:
            ids[id(node)] = node.step
        else:
            ids[id(node)] = next_id
            next_id += 1
    out.append("root " + " ".join(str(ids[id(c)]) for c in tree.children))
    for node in nodes:
        if node.step is None:
            children = " ".join(str(ids[id(c)]) for c in node.children)
            method = spell(node.branch or node.method or "")
            out.append(f"{ids[id(node)]} {line(node.name, node.args)} -> {method} {children}"
                       .rstrip())
    out.append("<==")
    return "\n".join(out) + "\n"
