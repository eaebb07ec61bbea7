"""The three transformations of the plan-transformations paper, as rewrites of
the top-level task list of a kitchen plan (``domains/kitchen.jshop``).

Each function gets the workspace and the applicability rule's satisfiers and
returns ``(description, paths)`` of what it rewrote, or None. The domain's own
subtasks (searching, fetching, delivering, loading-tray, ...) are reused, so the
planner re-plans the rewritten list with the domain's methods and operators:
arms are chosen by the ``fetching`` method (the first free one), and the
framework rolls a rewrite back if no valid plan results.

The rule set declares what the generic framework needs to know of the
domain: its applicability rules (:data:`RULES_FILE`) and the operators it
reads the plans by (:data:`KITCHEN`), the defaults of
:class:`~htn.transform.framework.Framework`.
"""

from __future__ import annotations

import itertools
from collections import OrderedDict
from pathlib import Path

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var

from .workspace import Unit, Vocabulary

RULES_FILE = Path(__file__).with_name("rules.jshop")

# the kitchen's operators that take or put down an object (the arm last) and
# the one that moves the robot between two areas
KITCHEN = Vocabulary(handling=frozenset({"!grasp", "!grasp-from", "!place"}), navigate="!navigate")

_fresh = itertools.count(1)


def _arm() -> Var:
    # a variable the top-level task list leaves unbound: the methods below bind
    # the arm they use (bindings propagate only downwards)
    return Var(f"?arm{next(_fresh)}", 0)


def _task(name: str, *args) -> S.TaskAtom:
    return S.TaskAtom(name, tuple(args))


def _transport(ws, path: str):
    unit = ws.unit_of(path)
    (atom,) = unit.tasks
    return unit, atom.args


def both_hands(ws, schemas):
    """Fetch two objects, one per arm, then deliver both: the delivery of the
    first is delayed until after the second has been fetched."""
    first, second = schemas[0]["first"], schemas[0]["second"]
    u1, (o1, f1, d1) = _transport(ws, first)
    u2, (o2, f2, d2) = _transport(ws, second)
    a1, a2 = _arm(), _arm()
    new1 = Unit([_task("searching", o1, f1), _task("fetching", o1, f1, a1)], [first], "both-hands")
    new2 = Unit(
        [
            _task("searching", o2, f2),
            _task("fetching", o2, f2, a2),
            _task("delivering", o1, d1, a1),
            _task("delivering", o2, d2, a2),
        ],
        [second],
        "both-hands",
    )
    ws.units = [new1 if u is u1 else new2 if u is u2 else u for u in ws.units]
    return f"{first} + {second}", [first, second]


def container(ws, schemas):
    """Open a container once before its first fetch and close it after its last."""
    by_container: OrderedDict = OrderedDict()
    for s in schemas:
        by_container.setdefault(s["c"], [])
        if s["t"] not in by_container[s["c"]]:
            by_container[s["c"]].append(s["t"])
    c, paths = next(iter(by_container.items()))
    order = [p for u in ws.units for p in u.paths if p in paths]
    area = next(a.args[1] for a in ws.instance.state if a.pred == "container" and a.args[0] == c)
    replaced = {}
    for i, path in enumerate(order):
        unit, (obj, src, dst) = _transport(ws, path)
        arm = _arm()
        tasks = [_task("searching", obj, src), _task("go-to", area)]
        if i == 0:
            tasks.append(_task("!open", c))
        tasks.append(_task("!grasp-from", obj, c, arm))
        if i == len(order) - 1:
            tasks.append(_task("!close", c))
        tasks.append(_task("delivering", obj, dst, arm))
        replaced[id(unit)] = Unit(tasks, [path], "container")
    ws.units = [replaced.get(id(u), u) for u in ws.units]
    return f"{c}: {', '.join(order)}", order


def tray(ws, schemas):
    """More than two transports from where a tray stands to one target: load
    them all on the tray, carry it, unload them."""
    groups: OrderedDict = OrderedDict()
    for s in schemas:
        groups.setdefault((s["tray"], s["from"], s["to"]), [])
        if s["t"] not in groups[(s["tray"], s["from"], s["to"])]:
            groups[(s["tray"], s["from"], s["to"])].append(s["t"])
    # the loop's variables are the group found, read after the break
    for (tray_, src, dst), paths in groups.items():  # noqa: B007
        if len(paths) > 2:
            break
    else:
        return None
    order = [p for u in ws.units for p in u.paths if p in paths]
    objects = [_transport(ws, p)[1][0] for p in order]
    tasks = []
    for obj in objects:
        tasks += [_task("searching", obj, src), _task("loading-tray", obj, src, tray_)]
    tasks.append(_task("carrying-tray", tray_, dst))
    tasks += [_task("unloading-tray", obj, tray_, dst) for obj in objects]
    first = ws.unit_of(order[0])
    rest = {id(ws.unit_of(p)) for p in order[1:]}
    merged = Unit(tasks, order, "tray")
    ws.units = [merged if u is first else u for u in ws.units if id(u) not in rest]
    return f"{tray_}: {', '.join(order)}", order


def register(fw) -> None:
    """Register the three rules with a :class:`~htn.transform.framework.Framework`,
    priorities tray > container > both-hands."""
    fw.register_transformation(both_hands, "(both-hands ?first ?second)", "both-hands")
    fw.register_transformation(container, "(container-shared ?t ?c)", "container")
    fw.register_transformation(tray, "(tray-transport ?t ?tray ?from ?to)", "tray")
    fw.prioritize_transformation("tray", "container")
    fw.prioritize_transformation("container", "both-hands")
