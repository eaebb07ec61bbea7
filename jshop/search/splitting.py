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
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import variables

from .jshop2_input import flat_tasks

PREFIX = "split:"  # the new tasks' names: the split method's label after it


def totally_ordered(methods: dict[str, list[S.Method]], root_order: object) -> bool:
    """Whether every task list of the problem is totally ordered."""
    if root_order is not True:
        return False
    return all(
        flat_tasks(b.tasks)[1] is True for ms in methods.values() for m in ms for b in m.branches
    )


def split_methods(methods: dict[str, list[S.Method]]) -> tuple[dict, dict, frozenset]:
    """``(methods, origin, made)``: the methods with each splittable one
    replaced by its two halves (see the module docstring), for each
    replacing method (by ``id``) the method it stands for, and the names of
    the tasks made."""
    out: dict[str, list[S.Method]] = {}
    origin: dict[int, S.Method] = {}
    made: set[str] = set()
    for name, ms in methods.items():
        kept = out.setdefault(name, [])
        for m in ms:
            if len(m.branches) != 1:  # JSHOP2's if-then-else: as written
                kept.append(m)
                continue
            # a name of its own: JSHOP2 may repeat a label, or name a task so
            new = PREFIX + m.branches[0].label
            k = 1
            while new in methods or new in made:
                k += 1
                new = f"{PREFIX}{m.branches[0].label}#{k}"
            halves = _split(m, new)
            if halves is None:
                kept.append(m)
                continue
            outer, inner = halves
            kept.append(outer)
            origin[id(outer)] = m
            out.setdefault(inner.name, []).append(inner)
            made.add(inner.name)
    return out, origin, frozenset(made)


def _split(m: S.Method, new: str) -> tuple[S.Method, S.Method] | None:
    if len(m.branches) != 1:
        return None
    b = m.branches[0]
    if b.pre.first or b.pre.sort_var is not None or not b.tasks.ordered:
        return None
    items, order = flat_tasks(b.tasks)
    if order is not True or len(items) < 2 or any(x.immediate for x in items):
        return None
    first, rest = items[0], items[1:]
    head = _indices(m.head.args)
    own = _indices(first.args)
    moved_vars = own - head - set().union(*(_indices(x.args) for x in rest))
    if not moved_vars:
        return None
    expr = b.pre.expr
    conjuncts = list(expr.items) if isinstance(expr, S.And) else [expr]
    moved, left = [], []
    for c in conjuncts:
        vs = _formula_vars(c)
        if vs is None:  # something this does not look into
            if _mentions(c, moved_vars):
                return None
            left.append(c)
        elif vs & moved_vars:
            if not _literal(c) or not vs <= own | head:
                return None
            moved.append(c)
        else:
            left.append(c)
    params = sorted((own | {v for c in moved for v in _formula_vars(c) or ()}) - moved_vars)
    var_of = _var_objects(items, m.head)
    label = b.label
    task = S.TaskAtom(new, tuple(var_of[i] for i in params), pos=first.pos)
    inner = S.Method(
        task,
        [
            S.Branch(
                label,
                S.Precondition(S.And(moved)),
                S.TaskList([first], True, b.tasks.pos),
                b.pos,
            )
        ],
        m.nvars,
        m.index,
        m.pos,
    )
    outer = S.Method(
        m.head,
        [
            S.Branch(
                label,
                S.Precondition(S.And(left), pos=b.pre.pos),
                S.TaskList([task, *rest], True, b.tasks.pos),
                b.pos,
            )
        ],
        m.nvars,
        m.index,
        m.pos,
    )
    return outer, inner


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


def _mentions(x, slots: set[int]) -> bool:
    """Whether a formula mentions any of the variable slots, anywhere."""
    stack = [x]
    while stack:
        y = stack.pop()
        if isinstance(y, (S.And, S.Or)):
            stack.extend(y.items)
        elif isinstance(y, S.Not):
            stack.append(y.expr)
        elif isinstance(y, S.ForAll):
            stack += [y.cond, y.then]
            if {v.index for v in y.vars} & slots:
                return True
        elif isinstance(y, S.Atom):
            if _indices(y.args) & slots:
                return True
        elif isinstance(y, S.Equal):
            if _indices((y.left, y.right)) & slots:
                return True
        else:
            return True  # unknown: assume it does
    return False


def _var_objects(items: list, head: S.TaskAtom) -> dict:
    """Slot -> a Var object of a method's subtasks and head (its name as written)."""
    out: dict = {}
    for x in items:
        for v in variables(x.args, []):
            out.setdefault(v.index, v)
    for v in variables(head.args, []):
        out.setdefault(v.index, v)
    return out
