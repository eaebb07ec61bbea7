"""UP expressions and effects as the HDDL model's formulas (:mod:`htn.jshop.readers.hddl_model`).

The conversion builds what the HDDL reader builds from text, so that
:mod:`htn.jshop.readers.hddl_domain` gives them HDDL's semantics (Höller et
al., AAAI 2020) unchanged:

* a parameter or quantified variable ``x`` is the variable ``?x``; an object
  is its name; a boolean fluent ``f(a, b)`` is the atom ``(f a b)``;
* ``and``, ``or``, ``not``, ``exists`` and ``forall`` are HDDL's;
  ``implies`` is ``(or (not a) b)`` and ``iff`` both implications;
* an **object fluent** ``f(a)`` of type ``T`` is the predicate ``(f a v)``
  holding of its one value ``v``: ``f(a) == b`` is ``(f a b)``; any other
  occurrence of ``f(a)`` in a condition stands for a new variable ``?v``
  bound by ``(exists (?v - T) (and (f a ?v) ...))`` around the literal
  (sound because the fluent has exactly one value in every state). The
  assignment ``f(a) := b`` deletes ``(f a ?v)`` for every ``?v`` and adds
  ``(f a b)`` (HDDL applies deletions before additions);
* ``e`` under ``forall`` and ``when`` becomes HDDL's ``forall`` and ``when``
  effects.

Anything else (numbers, time, fluent-valued assignments) raises
:class:`Unsupported`, which the engine reports as an unsupported problem.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var
from htn.jshop.readers.hddl_model import EffectForall, EffectWhen, Exists, Param


class Unsupported(Exception):
    """A part of a UP problem that htn cannot express; the message says which."""


def var_name(name: str) -> str:
    """The HDDL variable of a UP parameter or variable named ``name``."""
    return "?" + name


def type_of(t, what) -> tuple:
    """HDDL types of a UP type: a user type's name; other types are unsupported."""
    if not t.is_user_type():
        raise Unsupported(f"{what} has type {t}; htn supports object types only")
    return (t.name,)


def param(p, what: str = "") -> Param:
    """A UP parameter or variable as a typed HDDL parameter."""
    return Param(var_name(p.name), type_of(p.type, what or f"parameter {p.name}"))


class Expressions:
    """Converts the expressions of one problem; ``object_fluents`` maps the
    name of each object fluent to its value's type name."""

    def __init__(self, object_fluents: dict):
        self.object_fluents = object_fluents
        self.lifted = 0

    # ------------------------------------------------------------ terms
    def term(self, e, lifted: list | None = None):
        """A UP term as an HDDL term; an object fluent is replaced by a new
        variable whose defining atom goes to ``lifted`` (None: not allowed)."""
        if e.is_parameter_exp():
            return Var(var_name(e.parameter().name))
        if e.is_variable_exp():
            return Var(var_name(e.variable().name))
        if e.is_object_exp():
            return e.object().name
        if e.is_fluent_exp() and e.fluent().name in self.object_fluents and lifted is not None:
            self.lifted += 1
            name = e.fluent().name
            v = f"?{name}#{self.lifted}"
            args = tuple(self.term(a, lifted) for a in e.args)
            lifted.append((Param(v, (self.object_fluents[name],)), S.Atom(name, args + (Var(v),))))
            return Var(v)
        raise Unsupported(f"the term {e} is not an object, a parameter or a variable")

    # ------------------------------------------------------------ conditions
    def formula(self, e):
        """A UP boolean expression as an HDDL formula."""
        if e.is_and():
            return S.And([self.formula(x) for x in e.args])
        if e.is_or():
            return S.Or([self.formula(x) for x in e.args])
        if e.is_not():
            return S.Not(self.formula(e.arg(0)))
        if e.is_implies():
            return S.Or([S.Not(self.formula(e.arg(0))), self.formula(e.arg(1))])
        if e.is_iff():
            a, b = self.formula(e.arg(0)), self.formula(e.arg(1))
            return S.And([S.Or([S.Not(a), b]), S.Or([S.Not(b), a])])
        if e.is_exists() or e.is_forall():
            vs = [param(v, f"variable {v.name}") for v in e.variables()]
            body = self.formula(e.arg(0))
            return Exists(vs, body) if e.is_exists() else S.ForAll(vs, None, body)
        if e.is_bool_constant():
            return S.And([]) if e.bool_constant_value() else S.Or([])
        if e.is_fluent_exp():
            return self._literal(
                lambda lifted: S.Atom(e.fluent().name, tuple(self.term(a, lifted) for a in e.args)),
                e,
            )
        if e.is_equals():
            return self._literal(lambda lifted: self._equals(e, lifted), e)
        raise Unsupported(f"the condition {e} ({e.node_type.name.lower()}) is not supported")

    def _literal(self, build, e):
        if e.is_fluent_exp() and not e.fluent().type.is_bool_type():
            raise Unsupported(f"{e} is not a boolean condition")
        lifted: list = []
        literal = build(lifted)
        if not lifted:
            return literal
        return Exists([p for p, _ in lifted], S.And([a for _, a in lifted] + [literal]))

    def _equals(self, e, lifted: list):
        left, right = e.arg(0), e.arg(1)
        if not left.type.is_user_type():
            raise Unsupported(f"{e}: htn compares objects only")
        for f, other in ((left, right), (right, left)):
            if (
                f.is_fluent_exp()
                and f.fluent().name in self.object_fluents
                and not (other.is_fluent_exp() and other.fluent().name in self.object_fluents)
            ):
                args = tuple(self.term(a, lifted) for a in f.args)
                return S.Atom(f.fluent().name, args + (self.term(other, lifted),))
        return S.Equal(self.term(left, lifted), self.term(right, lifted))

    # ------------------------------------------------------------ effects
    def effects(self, action) -> list:
        """The HDDL effects of an instantaneous action, in its order."""
        out: list = []
        for eff in action.effects:
            items = self._assignment(eff)
            if eff.is_conditional():
                items = [EffectWhen([], self.formula(eff.condition), items)]
            if eff.is_forall():
                items = [EffectForall([param(v, f"variable {v.name}") for v in eff.forall], items)]
            out += items
        return out

    def _assignment(self, eff) -> list:
        if not eff.is_assignment():
            raise Unsupported(f"the effect {eff} is not an assignment")
        fluent = eff.fluent.fluent()
        args = tuple(self.term(a) for a in eff.fluent.args)
        value = eff.value
        if fluent.type.is_bool_type():
            if not value.is_bool_constant():
                raise Unsupported(
                    f"the effect {eff} assigns an expression; htn assigns true or false"
                )
            atom = S.Atom(fluent.name, args)
            return [atom] if value.bool_constant_value() else [S.Not(atom)]
        if fluent.name not in self.object_fluents:
            raise Unsupported(f"the effect {eff} assigns a {fluent.type} fluent")
        new = self.term(value)
        old = Param(f"?{fluent.name}#old", (self.object_fluents[fluent.name],))
        return [
            EffectForall([old], [S.Not(S.Atom(fluent.name, args + (Var(old.name),)))]),
            S.Atom(fluent.name, args + (new,)),
        ]
