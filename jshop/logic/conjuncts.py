"""The conjuncts of a conjunction as the mode compiler sees them
(:mod:`htn.jshop.logic.modes`): each classified once (a state atom, its
negation, a call, an assignment, an axiom, or anything else, which is asked
of the general engine), with its variables, the calls the generated code
makes, and the lengths a predicate's atoms can have (:func:`arities`)."""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.terms import CallTerm, Var, at_call, is_ground, variables
from htn.jshop.language.walk import walk_expr

ATOM, NOT_ATOM, CALL, ASSIGN, GENERAL, AXIOM, NOT_AXIOM = range(7)


def call_at(func, args, term):
    """A call term's value (arguments ground), placed at the call on error."""
    try:
        return func(args)
    except HtnError as exc:
        raise at_call(exc, term) from None


def call_nested(func, args, term):
    """Like :func:`call_at` for arguments that are themselves calls (whose
    value might not be ground): then the call stays a term, as in ``subst``."""
    if not is_ground(args):
        return CallTerm(term.name, term.func, args, term.pos)
    return call_at(func, args, term)


def term_vars(t, out: set) -> set:
    """Add the indices of the variables of a term or expression to ``out``."""
    if isinstance(
        t, (S.Atom, S.VarAtom, S.And, S.Or, S.Not, S.ForAll, S.Equal, S.Assign, S.CallExpr)
    ):
        walk_expr(t, lambda v: out.add(v.index))
    else:
        out.update(v.index for v in variables(t, []))
    return out


def evaluable(t) -> bool:
    """Whether ``t`` can be computed inline once its variables are bound."""
    tt = type(t)
    if tt is str or tt is float or tt is Var:
        return True
    if tt is tuple:
        return all(evaluable(x) for x in t)
    if tt is CallTerm:
        return all(evaluable(x) for x in t.args)
    return False


class Literal:
    """What one conjunct is, independently of the mode."""

    __slots__ = ("kind", "expr", "pred", "args", "vars", "binds", "facts")

    def __init__(self, expr, axioms: dict):
        self.expr = expr
        self.vars = term_vars(expr, set())
        # variables a satisfier may bind (a negation, forall or call binds none)
        self.binds = set() if isinstance(expr, (S.Not, S.ForAll, S.CallExpr)) else self.vars
        self.kind = GENERAL
        self.facts = False
        atom, kind = expr, ATOM
        if isinstance(expr, S.Not) and isinstance(expr.expr, S.Atom):
            atom, kind = expr.expr, NOT_ATOM
        if isinstance(atom, S.Atom):
            axs = axioms.get(atom.pred)
            plain = all(flat_term(a) for a in atom.args)
            # a flat list argument, like (on ?x ?z) in (goal (on ?x ?z)), is
            # matched element by element in the loop as well
            lists = all(
                flat_term(a) or (type(a) is tuple and all(map(flat_term, a))) for a in atom.args
            )
            if lists and (not axs or facts_only(axs)):
                self.kind, self.pred, self.args = kind, atom.pred, atom.args
                self.facts = bool(axs)
            elif plain:  # proved by its axioms, asked directly (Logic.solver)
                self.kind = AXIOM if kind == ATOM else NOT_AXIOM
                self.pred, self.args = atom.pred, atom.args
        elif isinstance(expr, S.CallExpr) and evaluable(expr.call):
            self.kind = CALL
        elif isinstance(expr, S.Assign) and evaluable(expr.term):
            self.kind = ASSIGN

    def sized(self, arities) -> bool:
        """Can an atom of another length be met (must the length be tested)?"""
        return self.kind in (ATOM, NOT_ATOM) and bool(
            self.facts or arities is None or arities.get(self.pred, set()) - {len(self.args)}
        )


def has_call(t) -> bool:
    tt = type(t)
    return tt is CallTerm or (tt is tuple and any(map(has_call, t)))


def flat_term(t) -> bool:
    """A symbol, a number, a variable or nil."""
    return type(t) in (str, float, Var) or t == ()


def always(pre: S.Precondition) -> bool:
    """An empty precondition (``nil``): exactly one satisfier, the binding itself."""
    e = pre.expr
    return isinstance(e, S.And) and not e.items and pre.sort_var is None


def facts_only(axioms: list) -> bool:
    """Whether a predicate's axioms are all facts (``(:- (diff-clr s h) nil)``),
    which :class:`htn.jshop.logic.engine.Logic` matches as one list of heads."""
    return all(is_ground(ax.head.args) and always(ax.branches[0].pre) for ax in axioms)


def flatten(items: list) -> list:
    out = []
    for x in items:
        if isinstance(x, S.And):
            out.extend(flatten(x.items))
        else:
            out.append(x)
    return out


def arities(domain: S.Domain, state) -> dict | None:
    """``pred -> {arity}``: the lengths the atoms of each predicate can have
    in ``state`` from now on (those already there and those of add lists);
    None when an add list has a variable atom (3.14), which can be anything."""
    out = {pred: {len(a) for a in lst} for pred, lst in state.atoms.items()}
    for ops in domain.operators.values():
        for op in ops:
            if op.add.var is not None:
                return None
            for item in op.add.items:
                if isinstance(item, S.Protection):
                    continue  # protects an atom, adds none
                for a in item.atoms if isinstance(item, S.EffectForAll) else [item]:
                    if not isinstance(a, S.Atom):
                        return None
                    out.setdefault(a.pred, set()).add(len(a.args))
    return out
