"""Parameter splitting before grounding (after PANDA's grounder, whose
``parametersplitting.cpp`` splits methods for the same reason; Behnke et
al., "On Succinct Groundings of HTN Planning Problems", AAAI 2020).

A method's ground instances are the product of its parameters' values,
although many of its parameters only matter to one subtask. IPC 2023's
Snake: ``move-long-snake`` takes the goal, the next cell, and the snake's
last two body cells, which only its first subtask ``move-long`` reads;
grounded as written it has cells x goals x 4 x body pairs instances (more
than 60 s and 1.7 GB on the 4-slot problem, unfinished). Split, the body
cells move into a new task of their own with one method::

    move-long-snake (?snake ?snakepos ?goalpos ?pos2):       cells x goals x 4
        (split:move-long-snake ?snake ?pos2 ?snakepos) (move ?snake ?pos2 ?goalpos)
    split:move-long-snake (?snake ?pos2 ?snakepos) + (?bodypos ?tailpos):
        precondition: the literals about ?bodypos and ?tailpos
        (move-long ?snake ?pos2 ?snakepos ?bodypos ?tailpos)

and the sum replaces the product (7 s to ground the 4-slot problem).

A method with one subtask is split too where that saves instances: IPC
2020's Minecraft-Player walks the player to the next cell of a way from
wherever it stands (``find-way-stop``: ``(player-at ?locP)``, then
``(walk ?locP ?locC)``), so every ``findway`` task had a method per cell the
player could stand on; split, they share one task per next cell (the
model of ``p-004-005-004-005``: 12.7 M methods in 126 s before, 0.41 M in
9 s).

The variables moved out (``E``) are those of the method's **first**
subtask that neither its head nor any other subtask mentions; the
precondition's conjuncts that mention them move with them, and may only
mention variables of that subtask or of the head besides (so that the
method left behind is never grounded more widely than before). Only where
the whole problem is totally ordered: there, the new task is the first of
the network once the method is applied, so it is decomposed next, in the
same state; the moved conjuncts are tested where the method's precondition
was. (In a partially ordered network another task could go first and
change the state in between.) The searches splice the new tasks out of
the task trees they return (``GroundModel.hidden``): the plans and trees
are those of the domain as written.

A later subtask's own variables split off too (given the dynamic
predicates) where the conjuncts about them are static, or were pulled up
from that subtask by the HDDL reader (see :func:`_among`): IPC 2020
Woodworking's ``process`` methods end with a ``do_colour`` of a part and a
machine of their own, whose ``(available ?part)`` was pulled up (instance
20: 68k ground methods instead of 539k).
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import variables

from .ground_formulas import mentions
from .jshop2_input import flat_tasks

PREFIX = "split:"  # the new tasks' names: the split method's label after it


def totally_ordered(methods: dict[str, list[S.Method]], root_order: object) -> bool:
    """Whether every task list of the problem is totally ordered."""
    if root_order is not True:
        return False
    return all(
        flat_tasks(b.tasks)[1] is True for ms in methods.values() for m in ms for b in m.branches
    )


def split_methods(
    methods: dict[str, list[S.Method]], dynamic: set[str] | None = None
) -> tuple[dict, dict, frozenset]:
    """``(methods, origin, made)``: the methods with each splittable one
    replaced by its parts (see the module docstring), for each replacing
    method (by ``id``) the method it stands for, and the names of the tasks
    made. With ``dynamic`` (the predicates some action changes), a later
    subtask's own variables are split off too where the conjuncts about
    them are static."""
    out: dict[str, list[S.Method]] = {}
    origin: dict[int, S.Method] = {}
    made: set[str] = set()

    def name_for(label: str, k: int) -> str:
        # a name of its own: JSHOP2 may repeat a label, or name a task so
        base = PREFIX + label + (f"@{k + 1}" if k else "")
        new, n = base, 1
        while new in methods or new in made:
            n += 1
            new = f"{base}#{n}"
        made.add(new)
        return new

    for name, ms in methods.items():
        kept = out.setdefault(name, [])
        for m in ms:
            parts = _split(m, name_for, dynamic)
            if parts is None:
                kept.append(m)
                continue
            outer, inners = parts
            kept.append(outer)
            origin[id(outer)] = m
            for inner in inners:
                out.setdefault(inner.name, []).append(inner)
    return out, origin, frozenset(made)


def _split(m: S.Method, name_for, dynamic: set[str] | None):
    """``(outer, inners)`` or None where nothing splits."""
    if len(m.branches) != 1:  # JSHOP2's if-then-else: as written
        return None
    b = m.branches[0]
    if b.pre.first or b.pre.sort_var is not None or not b.tasks.ordered:
        return None
    items, order = flat_tasks(b.tasks)
    if order is not True or not items or any(x.immediate for x in items):
        return None
    head = _indices(m.head.args)
    expr = b.pre.expr
    left = list(expr.items) if isinstance(expr, S.And) else [expr]
    var_of = _var_objects(items, m.head)
    tasks: list[S.TaskAtom | S.TaskList] = list(items)
    inners = []
    for k, sub in enumerate(items):
        if k and dynamic is None:
            break
        own = _indices(sub.args)
        others = set().union(*(_indices(x.args) for j, x in enumerate(items) if j != k))
        private = own - head - others
        if not private:
            continue
        moved, rest = _moved(left, private, own | head, None if k == 0 else dynamic, b.pre.pulled)
        if moved is None:
            continue
        params = sorted((own | {v for c in moved for v in _formula_vars(c) or ()}) - private)
        if len(items) == 1 and head <= set(params):
            continue  # the new task would have as many instances as the method
        left = rest
        task = S.TaskAtom(name_for(b.label, k), tuple(var_of[i] for i in params), pos=sub.pos)
        inners.append(
            S.Method(
                task,
                [
                    S.Branch(
                        b.label,
                        S.Precondition(S.And(moved)),
                        S.TaskList([sub], True, b.tasks.pos),
                        b.pos,
                    )
                ],
                m.nvars,
                m.index,
                m.pos,
            )
        )
        tasks[k] = task
    if not inners:
        return None
    outer = S.Method(
        m.head,
        [
            S.Branch(
                b.label,
                S.Precondition(
                    S.And(left),
                    pos=b.pre.pos,
                    pulled=tuple(p for p in b.pre.pulled if _among(p, tuple(left))),
                ),
                S.TaskList(tasks, True, b.tasks.pos),
                b.pos,
            )
        ],
        m.nvars,
        m.index,
        m.pos,
    )
    return outer, inners


def _moved(
    conjuncts: list,
    private: set[int],
    allowed: set[int],
    dynamic: set[str] | None,
    pulled: tuple = (),
):
    """``(moved, left)``: the conjuncts about ``private`` variables and the
    rest, or ``(None, None)`` if one of them cannot move: it is not a
    literal, mentions a variable outside ``allowed``, or (where ``dynamic``
    is given: a later subtask, tested later than the method) reads a
    predicate an action changes, unless it is one of the conditions
    ``pulled`` up from the subtask (see below)."""
    moved, left = [], []
    for c in conjuncts:
        vs = _formula_vars(c)
        if vs is None:  # something this does not look into
            if mentions(c, private):
                return None, None
            left.append(c)
        elif vs & private:
            if not _literal(c) or not vs <= allowed:
                return None, None
            if dynamic is not None and _predicate(c) in dynamic and not _among(c, pulled):
                return None, None
            moved.append(c)
        else:
            left.append(c)
    return moved, left


def _among(c, pulled: tuple) -> bool:
    """Whether ``c`` is one of the pulled-up conditions (the object itself).
    Such a literal mentions a private variable of one subtask only if it
    came from that subtask, and it may be tested when the subtask comes
    instead of when the method is applied: the subtask needs it then, and
    no earlier subtask can add it (or, negated, delete it), so it held
    when the method was applied exactly where it holds then, on every way
    to a plan (:mod:`htn.jshop.readers.pullup`)."""
    return any(c is p for p in pulled)


def _predicate(c) -> str | None:
    """A literal's predicate (None for an equality)."""
    if isinstance(c, S.Not):
        c = c.expr
    return c.pred if isinstance(c, S.Atom) else None


def _indices(args: tuple) -> set[int]:
    return {v.index for v in variables(args, [])}


def _literal(c) -> bool:
    if isinstance(c, S.Not):
        c = c.expr
    return isinstance(c, (S.Atom, S.Equal))


def _formula_vars(c) -> set[int] | None:
    """The variable slots of a literal, None for anything else."""
    if isinstance(c, S.Not):
        c = c.expr
    if isinstance(c, S.Atom):
        return _indices(c.args)
    if isinstance(c, S.Equal):
        return _indices((c.left, c.right))
    return None


def _var_objects(items: list, head: S.TaskAtom) -> dict:
    """Slot -> a Var object of a method's subtasks and head (its name as written)."""
    out: dict = {}
    for x in items:
        for v in variables(x.args, []):
            out.setdefault(v.index, v)
    for v in variables(head.args, []):
        out.setdefault(v.index, v)
    return out
