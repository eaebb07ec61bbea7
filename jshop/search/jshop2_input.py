"""JSHOP2 input for the grounded searches (``gbfs``, ``wastar``, ``auto``).

The grounder (:mod:`.grounding`) was written for HDDL; a JSHOP2 domain and
problem are planned by it under the manual's semantics where they keep to
what grounding can decide before the search:

* a method's branches are an if-then-else (manual 3.10): branch ``k``
  applies only in a state where no earlier branch's precondition has a
  satisfier; the grounder adds the negation of the earlier branches'
  preconditions (grounded under the head's binding) to branch ``k``'s;
* nested task lists, ``(a (:unordered b c) d)`` (manual 3.8), are
  one partial order of their atoms (:func:`flat_tasks`), with ``:unordered``
  interleaving as SHOP2's task networks do;
* a parameter no precondition binds ranges over every constant of the
  problem and the domain (the ``type:object`` facts HDDL's typing gives).

Refused, with the place and the reason (:class:`NotGroundable`; ``auto``
then runs depth-first search alone, ``gbfs`` and ``wastar`` say why):
axioms, an operator defined more than once, external calls (``call``,
``assign``, call terms), ``:first``
preconditions (which take one satisfier where grounding keeps all),
``:immediate`` tasks, protections, variable effect lists, costs that are no
number, a negation or a ``forall`` over a variable nothing bound before it
(JSHOP2 reads it as "no binding satisfies", grounding would bind it), an
operator whose effects use a variable its head does not bind, and a
``forall`` effect whose condition reads a predicate the operator deletes
before JSHOP2 evaluates it (the grounder evaluates it before the operator).
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import CallTerm, Dotted, Var, variables

from .ground_formulas import NotGroundable

OBJECT = "type:object"  # the static predicate that binds an unbound parameter


def checked_instance(domain: S.Domain, instance: S.ProblemInstance) -> S.ProblemInstance:
    """The instance as the grounder reads it (its state with a
    ``type:object`` fact for every constant), once the domain and the
    instance pass :func:`check`."""
    check(domain, instance)
    objects: dict = {}
    for atom in instance.state:
        _constants(atom.args, objects)
    for t in S.task_atoms(instance.tasks):
        _constants(t.args, objects)
    for element in domain.elements():
        for atom in _atoms(element):
            _constants(atom.args, objects)
    state = list(instance.state) + [S.Atom(OBJECT, (c,)) for c in objects]
    return S.ProblemInstance(
        state, instance.tasks, instance.pos, instance.goal, instance.goal_nvars, None, None
    )


def check(domain: S.Domain, instance: S.ProblemInstance) -> None:
    """Raise :class:`NotGroundable` (its text: the reason, at its place)
    for the first construct of the module docstring's list."""
    for axioms in domain.axioms.values():
        for ax in axioms:
            _refuse(ax.pos, f"axiom {ax.head.pred}: axioms (derived predicates)")
    _tasks(instance.tasks, "the problem's task list")
    for ops in domain.operators.values():
        if len(ops) > 1:  # JSHOP2 tries each; the grounder keeps one action per head
            _refuse(ops[1].pos, f"operator {ops[1].name} is defined {len(ops)} times")
        for op in ops:
            _operator(op)
    for ms in domain.methods.values():
        for m in ms:
            head = _vars(m.head.args)
            for b in m.branches:
                what = f"method {m.name} ({b.label})"
                _precondition(b.pre, set(head), what)
                _tasks(b.tasks, what)


def flat_tasks(tl: S.TaskList) -> tuple[list[S.TaskAtom], bool | S.PartialOrder]:
    """A task list's atoms in its written order and their order: True,
    False (none ordered) or the :class:`~htn.jshop.language.syntax.PartialOrder`
    of a nested list (each atom's predecessors: every atom of an earlier
    member of an ordered list it is in)."""
    if all(isinstance(x, S.TaskAtom) for x in tl.items):
        return list(tl.items), tl.order_flag  # type: ignore[arg-type]
    atoms: list[S.TaskAtom] = []
    preds: list[set[int]] = []

    def walk(x, before: frozenset) -> list[int]:
        if isinstance(x, S.TaskAtom):
            atoms.append(x)
            preds.append(set(before))
            return [len(atoms) - 1]
        out: list[int] = []
        if x.ordered:
            done = set(before)
            for y in x.items:
                got = walk(y, frozenset(done))
                done.update(got)
                out += got
        else:
            for y in x.items:
                out += walk(y, before)
        return out

    walk(tl, frozenset())
    if all(p == set(range(i)) for i, p in enumerate(preds)):
        return atoms, True
    return atoms, S.PartialOrder(tuple(tuple(sorted(p)) for p in preds))


# ------------------------------------------------------------ the checks


def _refuse(pos, why: str):
    where = f"{pos.file}:{pos.line}:{pos.col}: " if pos is not None and pos.file else ""
    raise NotGroundable(f"{where}{why}")


def _vars(t) -> set[int]:
    return {v.index for v in variables(t, [])}


def _has_call(t) -> bool:
    if type(t) is CallTerm:
        return True
    if type(t) is tuple:
        return any(_has_call(x) for x in t)
    if type(t) is Dotted:
        return any(_has_call(x) for x in t.items) or _has_call(t.tail)
    return False


def _tasks(tl: S.TaskList, what: str) -> None:
    for t in S.task_atoms(tl):
        if t.immediate:
            _refuse(t.pos, f"{what}: an :immediate task ({t.name})")
        if _has_call(t.args):
            _refuse(t.pos, f"{what}: a call term in task {t.name}")


def _precondition(pre: S.Precondition, bound: set[int], what: str) -> set[int]:
    if pre.first:
        _refuse(pre.pos, f"{what}: a :first precondition")
    return _formula(pre.expr, bound, what)


def _formula(e, bound: set[int], what: str) -> set[int]:
    """The variables bound after ``e`` is satisfied, left to right."""
    if isinstance(e, S.Atom):
        if _has_call(e.args):
            _refuse(e.pos, f"{what}: a call term in ({e.pred} ...)")
        return bound | _vars(e.args)
    if isinstance(e, S.Equal):
        return bound | _vars((e.left, e.right))
    if isinstance(e, S.And):
        for x in e.items:
            bound = _formula(x, bound, what)
        return bound
    if isinstance(e, S.Or):
        after = [_formula(x, set(bound), what) for x in e.items]
        return set.intersection(*after) if after else bound
    if isinstance(e, S.Not):
        _formula(e.expr, bound, what)
        _closed(e.expr, bound, e.pos, what, "a negation")
        return bound
    if isinstance(e, S.ForAll):
        inner = bound | {v.index for v in e.vars}
        _formula(e.then, _formula(e.cond, inner, what), what)
        _closed(e, inner, e.pos, what, "a forall")
        return bound
    kind = {"Assign": "an assign", "CallExpr": "a call"}.get(type(e).__name__)
    _refuse(getattr(e, "pos", None), f"{what}: {kind or type(e).__name__} in a precondition")
    return bound


def _closed(e, bound: set[int], pos, what: str, kind: str) -> None:
    free: list[Var] = []
    _free(e, free)
    loose = [v for v in free if v.index not in bound]
    if loose:
        _refuse(pos, f"{what}: {kind} over {loose[0].name}, which nothing binds before it")


def _free(e, out: list[Var]) -> None:
    if isinstance(e, S.Atom):
        variables(e.args, out)
    elif isinstance(e, S.Equal):
        variables((e.left, e.right), out)
    elif isinstance(e, (S.And, S.Or)):
        for x in e.items:
            _free(x, out)
    elif isinstance(e, S.Not):
        _free(e.expr, out)
    elif isinstance(e, S.ForAll):
        inner: list[Var] = []
        _free(e.cond, inner)
        _free(e.then, inner)
        own = {v.index for v in e.vars}
        out.extend(v for v in inner if v.index not in own)


def _operator(op: S.Operator) -> None:
    what = f"operator {op.name}"
    head = _vars(op.head.args)
    _precondition(op.pre, set(head), what)
    if type(op.cost) is not float:
        _refuse(op.pos, f"{what}: a cost that is not a number")
    _forall_order(op, what)
    for eff in (op.delete, op.add):
        if eff.var is not None:
            _refuse(op.pos, f"{what}: a variable effect list")
        for item in eff.items:
            if isinstance(item, S.Protection):
                _refuse(item.pos, f"{what}: a protection")
            if isinstance(item, S.EffectForAll):
                own = {v.index for v in item.vars}
                inner = _formula(item.cond, head | own, what)
                used: list[Var] = []
                _free(item.cond, used)
                for a in item.atoms:
                    variables(a.args, used)
                loose = [v for v in used if v.index not in inner]
            else:
                loose = [v for v in variables(item.args, []) if v.index not in head]
                if _has_call(item.args):
                    _refuse(item.pos, f"{what}: a call term in an effect")
            if loose:
                _refuse(
                    getattr(item, "pos", None) or op.pos,
                    f"{what}: effect variable {loose[0].name} is not a parameter of its head "
                    "(JSHOP2 tries each satisfier; grounding needs the head to bind it)",
                )


def _forall_order(op: S.Operator, what: str) -> None:
    """JSHOP2 evaluates a delete list's ``forall`` after the atoms before it
    are deleted, an add list's after every deletion (manual 5.2.1); the
    grounder evaluates every condition before the operator, as PDDL does.
    The two agree unless a condition reads a predicate deleted before it."""
    deleted: set[str] = set()
    for eff, before_all in ((op.delete, False), (op.add, True)):
        if before_all:
            deleted = _effect_preds(op.delete.items)
        for item in eff.items:
            if isinstance(item, S.EffectForAll):
                read = {a.pred for a in _atoms_of(item.cond)}
                if read & deleted:
                    _refuse(
                        item.pos,
                        f"{what}: a forall whose condition reads {sorted(read & deleted)[0]}, "
                        "which the operator deletes before JSHOP2 evaluates it",
                    )
            if not before_all:
                deleted |= _effect_preds([item])


def _effect_preds(items: list) -> set[str]:
    out: set[str] = set()
    for item in items:
        if isinstance(item, S.Atom):
            out.add(item.pred)
        elif isinstance(item, S.EffectForAll):
            out.update(a.pred for a in item.atoms if isinstance(a, S.Atom))
    return out


def _atoms_of(e) -> list:
    """The atoms of a formula, negated ones and those under forall included."""
    out, stack = [], [e]
    while stack:
        x = stack.pop()
        if isinstance(x, S.Atom):
            out.append(x)
        elif isinstance(x, (S.And, S.Or)):
            stack.extend(x.items)
        elif isinstance(x, S.Not):
            stack.append(x.expr)
        elif isinstance(x, S.ForAll):
            stack.extend((x.cond, x.then))
    return out


def _atoms(element):
    """The atoms of a domain element's conditions, effects and tasks (for
    the constants written in it)."""
    pres: list = []
    if isinstance(element, S.Operator):
        pres = [element.pre.expr]
        for eff in (element.delete, element.add):
            for item in eff.items:
                if isinstance(item, S.Atom):
                    yield item
                elif isinstance(item, S.EffectForAll):
                    pres.append(item.cond)
                    yield from item.atoms
    elif isinstance(element, S.Method):
        for b in element.branches:
            pres.append(b.pre.expr)
            yield from S.task_atoms(b.tasks)
    for e in pres:
        yield from _atoms_of(e)


def _constants(args: tuple, out: dict) -> None:
    for a in args:
        if type(a) is not Var and not variables(a, []):
            out[a] = None
