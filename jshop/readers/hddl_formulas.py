"""HDDL formulas as the planner's expressions (:mod:`htn.jshop.readers.hddl_domain`):
variables numbered per element, types as type predicates, quantifiers and
``imply``, and the order in which a method's or action's conjuncts are tested
so that JSHOP2's left-to-right evaluation binds variables early
(:func:`order_conjuncts`)."""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.terms import Var, variables
from htn.jshop.language.walk import walk_expr

from .hddl_model import Exists


class Scope:
    """Variable numbering of one domain element (operator, method, goal):
    JSHOP2's binding array slot of each variable (manual 5.1.1)."""

    def __init__(self):
        self.slots: dict = {}
        self.renamed = 0

    def var(self, name: str) -> Var:
        return Var(name, self.slots.setdefault(name, len(self.slots)))

    def fresh(self, name: str) -> str:
        """A new name for a quantified variable, apart from every other."""
        self.renamed += 1
        return f"{name}#{self.renamed}"

    @property
    def size(self) -> int:
        return len(self.slots)


# ------------------------------------------------------------------ formulas


class Formulas:
    """Converts model formulas into syntax expressions within one scope.

    ``names`` maps a variable's written name to its name in the scope
    (quantified variables are renamed apart); ``outer`` collects the slots
    that the element's precondition must bind (its parameters and the
    variables of ``exists`` at the top level of the precondition).
    """

    def __init__(self, scope: Scope, predicates: dict | None = None):
        self.scope = scope
        self.predicates = predicates  # name -> params, to check atoms (domain only)
        self.outer: set = set()

    def term(self, x, names: dict, pos):
        if isinstance(x, Var):
            if x.name not in names:
                raise HtnError.at(
                    pos, f"variable {x.name} is not declared here (not a parameter nor quantified)"
                )
            return self.scope.var(names[x.name])
        return x

    def atom(self, e: S.Atom, names: dict) -> S.Atom:
        if self.predicates is not None:
            params = self.predicates.get(e.pred)
            if params is None:
                raise HtnError.at(e.pos, f"unknown predicate {e.pred}")
            if len(params) != len(e.args):
                raise HtnError.at(
                    e.pos,
                    f"predicate {e.pred} takes {len(params)} argument(s), given {len(e.args)}",
                )
        return S.Atom(e.pred, tuple(self.term(a, names, e.pos) for a in e.args), e.pos)

    def quantify(self, params, names: dict, pos) -> tuple[list, list, dict]:
        """Rename quantified variables apart: (vars, their type conditions, names)."""
        names = dict(names)
        vs, conds = [], []
        for p in params:
            names[p.name] = self.scope.fresh(p.name)
            v = self.scope.var(names[p.name])
            vs.append(v)
            conds.append(type_condition(v, p.types, p.pos or pos))
        return vs, conds, names

    def expr(self, e, names: dict):
        if e is None:
            return S.And([])
        if isinstance(e, S.Atom):
            return self.atom(e, names)
        if isinstance(e, S.And):
            return S.And([self.expr(x, names) for x in e.items], e.pos)
        if isinstance(e, S.Or):
            return S.Or([self.expr(x, names) for x in e.items], e.pos)
        if isinstance(e, S.Not):
            return S.Not(self.expr(e.expr, names), e.pos)
        if isinstance(e, S.Equal):
            return S.Equal(self.term(e.left, names, e.pos), self.term(e.right, names, e.pos), e.pos)
        if isinstance(e, Exists):
            _, conds, inner = self.quantify(e.vars, names, e.pos)
            return S.And(conds + [self.expr(e.expr, inner)], e.pos)
        if isinstance(e, S.ForAll):
            vs, conds, inner = self.quantify(e.vars, names, e.pos)
            return S.ForAll(
                vs, S.And(conds) if len(conds) != 1 else conds[0], self.expr(e.then, inner), e.pos
            )
        raise HtnError.at(getattr(e, "pos", None), "unsupported formula")  # pragma: no cover

    def conjuncts(self, e, names: dict) -> tuple[list, list]:
        """The top-level conjuncts of a precondition and the type conditions
        of its top-level ``exists`` variables (which join ``outer``)."""
        if e is None:
            return [], []
        if isinstance(e, S.And):
            conds, types = [], []
            for x in e.items:
                c, t = self.conjuncts(x, names)
                conds += c
                types += t
            return conds, types
        if isinstance(e, Exists):
            vs, types, inner = self.quantify(e.vars, names, e.pos)
            self.outer.update(v.index for v in vs)
            conds, more = self.conjuncts(e.expr, inner)
            return conds, types + more
        return [self.expr(e, names)], []


def type_predicate(t: str) -> str:
    """The predicate that holds of the objects of type ``t``."""
    return "type:" + t


def type_condition(v: Var, types: tuple, pos) -> object:
    """``(type:t ?v)``, or a disjunction for ``(either t1 t2)``."""
    atoms = [S.Atom(type_predicate(t), (v,), pos) for t in types]
    return atoms[0] if len(atoms) == 1 else S.Or(atoms, pos)


# ------------------------------------------------------------------ ordering


def _slots(e) -> set:
    """The variable slots an expression mentions (bound or quantified)."""
    out: set = set()
    walk_expr(e, lambda v: out.add(v.index))
    return out


def order_conjuncts(conds: list, types: list, bound: set, outer: set) -> list:
    """Order a precondition's conjuncts for JSHOP2's left-to-right evaluation.

    Greedy: every literal whose outer variables are all bound is emitted at
    once as a test (written order kept); otherwise the positive atom (or an
    equality with one side bound) with the most bound arguments binds next;
    when none is left, the next type condition enumerates its variable's
    objects. Negations, disjunctions, ``forall`` and equalities thus only see
    bound variables, which is the PDDL meaning of a method's or action's
    existentially bound parameters.
    """
    bound = set(bound)
    pending, tpending, out = list(conds), list(types), []
    while pending or tpending:
        for e in [e for e in pending if _is_test(e, bound, outer)]:
            out.append(e)
            pending.remove(e)
        for e in [e for e in tpending if _slots(e) <= bound]:
            out.append(e)
            tpending.remove(e)
        best = _best_generator(pending, bound)
        if best is not None:
            pending.remove(best)
        elif tpending:
            best = tpending.pop(0)
        elif pending:  # nothing binds what is left: keep it as written
            out += pending
            break
        else:
            break
        out.append(best)
        bound |= _slots(best)
    return out


def _is_test(e, bound: set, outer: set) -> bool:
    need = _slots(e) & outer if not isinstance(e, (S.Atom, S.Equal)) else _slots(e)
    return need <= bound


def _best_generator(pending: list, bound: set):
    best, best_key = None, None
    for i, e in enumerate(pending):
        if isinstance(e, S.Equal):
            sides = [type(x) is not Var or x.index in bound for x in (e.left, e.right)]
            key = (0, 0, i) if any(sides) else None
        elif isinstance(e, S.Atom):
            vs = {v.index for v in variables(e.args, [])}
            unbound = len(vs - bound)
            key = (1 if len(vs) - unbound == 0 else 0, unbound, i)
        else:
            key = None
        if key is not None and (best_key is None or key < best_key):
            best, best_key = e, key
    return best
