"""Pull-up of preconditions: necessary conditions a method can test at once.

HyperTensioN's "pullup" (Magnaguagno et al., IPC 2020), with its "typredicate"
done by type reasoning instead of renaming predicates. A literal that a
subtask needs is a necessary condition of the method itself when no earlier
subtask can change it:

* ``(p a b)`` needed by subtask *i* held when the method was applied if no
  subtask before *i* can add a ``p`` atom that unifies with it, given the
  types of the arguments (Transport's ``drive`` adds ``(at vehicle
  location)``, which cannot make ``(at package location)`` true);
* ``(not (p a b))`` likewise if none can delete one.

What a subtask needs: an action's precondition literals over its parameters,
or for a compound task the literals every one of its methods tests (their
preconditions and what they pulled up, over the task's parameters), computed
to a fixpoint. Testing these literals in the method's precondition binds its
free parameters early (the package's location in Transport's ``deliver``)
and cuts decompositions that would fail only after a long detour. Plans are
unchanged: only branches without a plan are cut.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var

from .hddl_model import HDomain, MethodDef
from .hddl_order import linearise


def pulled_conditions(h: HDomain, ancestors: dict, extra=()) -> dict:
    """``id(method) -> [literal]`` in the method's own terms (model formulas),
    for the domain's methods and ``extra`` ones (a problem's root method)."""
    return _Pullup(h, ancestors, list(extra)).run()


class _Pullup:
    def __init__(self, h: HDomain, ancestors: dict, extra: list):
        self.h = h
        self.methods = h.methods + extra
        self.ancestors = ancestors
        self.const_types = {c.name: c.types for c in h.constants}
        self.action_effects = {a.name: list(self._effects(a)) for a in h.actions.values()}
        self.reachable = self._reachable_actions()

    # ------------------------------------------------------------ types
    def _compatible(self, ta, tb) -> bool:
        if ta is None or tb is None:
            return True
        for a in ta:
            for b in tb:
                if a == b or a in self.ancestors.get(b, ()) or b in self.ancestors.get(a, ()):
                    return True
        return False

    def _arg_types(self, args, types_of: dict) -> tuple:
        return tuple(
            types_of.get(x.name) if isinstance(x, Var) else self.const_types.get(x) for x in args
        )

    # ------------------------------------------------------------ effects
    def _effects(self, a):
        """(positive, pred, argument types) of each atom an action may change."""
        types = {p.name: p.types for p in a.params}
        stack = [(a.effect, types)]
        while stack:
            e, ts = stack.pop()
            if isinstance(e, list):
                stack.extend((x, ts) for x in e)
            elif hasattr(e, "effect"):  # forall / when
                inner = dict(ts)
                for p in getattr(e, "vars", ()):
                    inner[p.name] = p.types
                stack.append((e.effect, inner))
            elif isinstance(e, S.Not):
                yield False, e.expr.pred, self._arg_types(e.expr.args, ts)
            elif isinstance(e, S.Atom):
                yield True, e.pred, self._arg_types(e.args, ts)

    def _reachable_actions(self) -> dict:
        """Task name -> the actions its decompositions may contain."""
        subtasks: dict = {}
        for m in self.h.methods:
            subtasks.setdefault(m.task.name, set()).update(s.name for s in m.network.subtasks)
        out = {}
        for task in subtasks:
            seen, stack, actions = set(), [task], set()
            while stack:
                t = stack.pop()
                if t in self.h.actions:
                    actions.add(t)
                elif t not in seen:
                    seen.add(t)
                    stack.extend(subtasks.get(t, ()))
            out[task] = actions
        return out

    def _changes(self, name: str) -> list:
        if name in self.h.actions:
            return self.action_effects[name]
        return [e for a in self.reachable.get(name, ()) for e in self.action_effects[a]]

    def _threatens(self, changes, positive: bool, pred: str, arg_types: tuple) -> bool:
        for sign, p, types in changes:
            if (
                sign == positive
                and p == pred
                and len(types) == len(arg_types)
                and all(self._compatible(a, b) for a, b in zip(types, arg_types))
            ):
                return True
        return False

    # ------------------------------------------------------------ literals
    @staticmethod
    def _literals(expr):
        """Top-level (positive, atom) literals of a precondition."""
        stack = [expr]
        while stack:
            e = stack.pop()
            if isinstance(e, S.And):
                stack.extend(reversed(e.items))
            elif isinstance(e, S.Atom):
                yield True, e
            elif isinstance(e, S.Not) and isinstance(e.expr, S.Atom):
                yield False, e.expr

    def _needs(self, st, necessary: dict) -> list:
        """What subtask ``st`` needs, as (positive, pred, args, pos) in the caller's terms."""
        if st.name in self.h.actions:
            a = self.h.actions[st.name]
            if len(a.params) != len(st.args):
                return []  # an arity error, reported with its place later
            params = {p.name: i for i, p in enumerate(a.params)}
            out = []
            for positive, atom in self._literals(a.pre):
                args = []
                for x in atom.args:
                    if isinstance(x, Var):
                        if x.name not in params:
                            break
                        args.append(st.args[params[x.name]])
                    else:
                        args.append(x)
                else:
                    out.append((positive, atom.pred, tuple(args), atom.pos))
            return out
        task = self.h.tasks.get(st.name)
        if task is None or len(task.params) != len(st.args):
            return []
        return [
            (positive, pred, tuple(st.args[i] if type(i) is int else i[1] for i in args), pos)
            for positive, pred, args, pos in necessary.get(st.name, ())
        ]

    # ------------------------------------------------------------ the fixpoint
    def run(self) -> dict:
        pulled: dict = {id(m): [] for m in self.methods}
        necessary: dict = {}
        for _ in range(20):
            necessary = self._necessary(pulled)
            changed = False
            for m in self.methods:
                found = self._pull(m, necessary)
                if len(found) != len(pulled[id(m)]):
                    pulled[id(m)] = found
                    changed = True
            if not changed:
                break
        return {k: [_formula(lit) for lit in v] for k, v in pulled.items()}

    def _pull(self, m: MethodDef, necessary: dict) -> list:
        types = {p.name: p.types for p in m.params}
        own = {(sign, a.pred, _key(a.args)) for sign, a in self._literals(m.pre)}
        changes: list = []
        out, seen = [], set()
        for st in m.network.subtasks if m.network.ordered else _ordered(m):
            for positive, pred, args, pos in self._needs(st, necessary):
                key = (positive, pred, _key(args))
                if key in own or key in seen:
                    continue
                if not self._threatens(changes, positive, pred, self._arg_types(args, types)):
                    seen.add(key)
                    out.append((positive, pred, args, pos))
            changes += self._changes(st.name)
        return out

    def _necessary(self, pulled: dict) -> dict:
        """Task -> literals over its parameter positions that all its methods test."""
        per_task: dict = {}
        for m in self.methods:
            head: dict = {}
            for i, x in enumerate(m.task.args):
                if isinstance(x, Var):
                    head.setdefault(x.name, i)
            lits = set()
            literals = [(p, a.pred, a.args, a.pos) for p, a in self._literals(m.pre)]
            for positive, pred, args, pos in literals + pulled[id(m)]:
                mapped = []
                for x in args:
                    if isinstance(x, Var):
                        if x.name not in head:
                            break
                        mapped.append(head[x.name])
                    else:
                        mapped.append(("const", x))
                else:
                    lits.add((positive, pred, tuple(mapped), pos))
            per_task.setdefault(m.task.name, []).append(lits)
        out = {}
        for task, sets in per_task.items():
            keys = set.intersection(*({(p, q, a) for p, q, a, _ in s} for s in sets))
            out[task] = [lit for lit in sorted(sets[0], key=_order) if lit[:3] in keys]
        return out


def _key(args) -> tuple:
    """Arguments compared by name (model variables are distinct objects)."""
    return tuple(("?", x.name) if isinstance(x, Var) else x for x in args)


def _order(lit) -> tuple:
    pos = lit[3]
    return (pos.line, pos.col) if pos is not None else (0, 0)


def _ordered(m: MethodDef) -> list:
    return linearise(m.network, f"method {m.name}", m.pos)


def _formula(lit):
    positive, pred, args, pos = lit
    atom = S.Atom(pred, args, pos)
    return atom if positive else S.Not(atom, pos)
