"""Operators applied to the state (manual 5.2.1), compiled once per operator.

Applying an operator instance deletes the atoms of its delete list, then adds
those of its add list; it fails, leaving the state as it was, if it would
delete a protected atom; ``(:protection a)`` in the add list protects ``a``
and in the delete list cancels one protection (manual 3.9). A delete list's
``forall`` element is evaluated while the atoms before it are already deleted
and the add list after every deletion, as in JSHOP2; an HDDL action
(``Operator.effects_in_prestate``) evaluates every condition in the state
before the action, as PDDL does.

Each operator's delete and add lists are compiled into small programs when
the planner starts: plain atoms become ``(pred, substituter)`` pairs, the common case
that needs no condition at all.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import PlanningError
from htn.jshop.language.terms import atom_from_term, shown_term, source_atom

from . import warming as warm
from .caches import cache
from .codegen import described
from .state import Change

_ATOM, _VAR_ATOM, _PROTECT, _FORALL = range(4)


class Operators:
    """The operators of one domain, applied to one (mutable) state."""

    def __init__(self, state, logic):
        self.state = state
        self.logic = logic
        self._programs: dict = {}  # id(op) -> (plain dels, plain adds, dels, adds, op)
        self._general: dict = {}  # id(op) -> (dels, adds) compiled in general form
        for ops in logic.domain.operators.values():  # compiled before searching
            for op in ops:
                self.program(op)

    def program(self, op: S.Operator) -> tuple:
        prog = self._programs.get(id(op))
        if prog is None:
            dels, adds = _plain_lists(op)
            if dels is not None and adds is not None:
                prog = (dels, adds, None, None, op)
            else:
                prog = (dels, adds, self._compile(op.delete, op), self._compile(op.add, op), op)
            self._programs[id(op)] = prog
        return prog

    def _compile(self, eff: S.Effects, op: S.Operator):
        if eff.var is not None:
            return eff.var
        out: list = []
        for item in eff.items:
            if isinstance(item, S.EffectForAll):
                out.append(
                    (
                        _FORALL,
                        self.logic.expr(item.cond),
                        [_atom_program(a, op) for a in item.atoms],
                    )
                )
            elif isinstance(item, S.Protection):
                out.append((_PROTECT, _atom_program(item.atom, op), None))
            else:
                out.append(_atom_program(item, op))
        return out

    # ------------------------------------------------------------ applying
    def apply(self, op: S.Operator, env: list):
        """Apply ``op`` under ``env``: ``(change, True)``, or ``(change, False)``
        if it would delete a protected atom (the caller undoes ``change``)."""
        change = Change()
        state = self.state
        prog = self._programs.get(id(op)) or self.program(op)
        dels, adds = prog[0], prog[1]
        if dels is not None and adds is not None:  # no conditions: nothing to evaluate
            protections = state.protections
            deleted, added = change.deleted, change.added
            for pred, bind in dels:
                args = bind(env)
                if (pred, args) in protections:
                    return change, False
                i = state.delete(pred, args)
                if i != -1:
                    deleted.append((pred, args, i))
            for pred, bind in adds:
                args = bind(env)
                if state.add(pred, args):
                    added.append((pred, args))
            return change, True
        deletions = self.atoms(prog[2], env, op)
        additions = self.atoms(prog[3], env, op)
        if op.effects_in_prestate:
            deletions, additions = list(deletions), list(additions)
        protections, deleted = state.protections, change.deleted
        for pred, args in deletions:
            if pred is None:  # a protection condition to cancel
                p, a = args
                if state.unprotect(p, a):
                    if not change.unprotected:
                        change.unprotected = []
                    change.unprotected.append((p, a))
                continue
            if protections and (pred, args) in protections:
                return change, False
            i = state.delete(pred, args)
            if i != -1:
                deleted.append((pred, args, i))
        for pred, args in additions:
            if pred is None:
                p, a = args
                state.protect(p, a)
                if not change.protected:
                    change.protected = []
                change.protected.append((p, a))
                continue
            if state.add(pred, args):
                change.added.append((pred, args))
        return change, True

    def atoms(self, program, env: list, op):
        """Ground atoms of a compiled delete/add list; protections come as
        ``(None, atom)``. Lazy: see the module docstring."""
        if not isinstance(program, list):  # the list is a variable (3.14)
            lst = env[program.index]
            if type(lst) is not tuple:
                raise PlanningError.at(
                    op.pos,
                    f"the effect list variable {program.name} "
                    f"of {op.name} is bound to {shown_term(lst)}",
                )
            for t in lst:
                yield atom_from_term(t, op.pos)
            return
        for kind, a, b in program:
            if kind == _ATOM:
                yield a, b(env)
            elif kind == _FORALL:
                for nb in a(env):
                    for atom in b:
                        yield _ground(atom, nb)
            elif kind == _PROTECT:
                yield None, _ground(a, env)
            else:
                yield _var_atom(a, env)

    def effects(self, op: S.Operator, env: list) -> tuple[list, list]:
        """The ground atoms ``op`` would delete and add under ``env``, in the
        current state (protections left out)."""
        general = self._general.get(id(op))
        if general is None:
            general = self._general[id(op)] = (
                self._compile(op.delete, op),
                self._compile(op.add, op),
            )
        dels = [a for a in self.atoms(general[0], env, op) if a[0] is not None]
        adds = [a for a in self.atoms(general[1], env, op) if a[0] is not None]
        return dels, adds


_PLAIN = cache()  # id(op) -> (dels, adds): the same for every planner


def _plain_lists(op: S.Operator) -> tuple:
    return _PLAIN.make(op, lambda: (_plain(op.delete, op), _plain(op.add, op)))


def _plain(eff: S.Effects, op: S.Operator) -> list | None:
    """``[[pred, substituter]]`` for a list of plain atoms, else None (general
    case). The substituters are warming: compiled ones replace them in place."""
    if eff.var is not None or not all(isinstance(i, S.Atom) for i in eff.items):
        return None
    out = []
    for i in eff.items:
        entry = [i.pred, None]
        entry[1] = _substituter(i, op, lambda f, entry=entry: entry.__setitem__(1, f))
        out.append(entry)
    return out


def _substituter(a: S.Atom, op: S.Operator, install):
    return warm.substituter(
        a.args,
        lambda: described(f"effect {source_atom(a.pred, a.args)} of {op.name}", a.pos or op.pos),
        install,
    )


def _atom_program(a, op: S.Operator) -> list:
    if isinstance(a, S.VarAtom):
        return [_VAR_ATOM, a, None]
    entry = [_ATOM, a.pred, None]
    entry[2] = _substituter(a, op, lambda f: entry.__setitem__(2, f))
    return entry


def _ground(atom: tuple, env: list) -> tuple:
    kind, a, b = atom
    if kind == _ATOM:
        return a, b(env)
    return _var_atom(a, env)


def _var_atom(a: S.VarAtom, env: list) -> tuple:
    t = env[a.var.index]
    if t is None:
        raise PlanningError.at(a.pos, f"effect variable {a.var.name} is not bound")
    return atom_from_term(t, a.pos)
