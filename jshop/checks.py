"""Static checks of a domain and a problem before planning.

Errors stop planning; warnings point at likely domain bugs but keep JSHOP2's
behaviour. Where JSHOP2 itself accepts the input we only warn: a task used in
a method body with no method or operator simply cannot be achieved there
(the JSHOP2 ``test`` example relies on that), and a variable a method passes
down unbound is how bindings fail to propagate upwards (``propagation``).
"""
from __future__ import annotations

from dataclasses import dataclass

from . import syntax as S
from .errors import HtnError
from .parser import _walk_expr, _walk_pre, _walk_term


@dataclass
class Warning_:
    pos: S.Pos | None
    message: str

    def __str__(self) -> str:
        return f"{self.pos}: warning: {self.message}" if self.pos else f"warning: {self.message}"


def _arities(domain: S.Domain) -> dict[str, set[int]]:
    out: dict[str, set[int]] = {}
    for name, ops in domain.operators.items():
        out.setdefault(name, set()).update(len(o.head.args) for o in ops)
    for name, ms in domain.methods.items():
        out.setdefault(name, set()).update(len(m.head.args) for m in ms)
    return out


def _describe_task(t: S.TaskAtom) -> str:
    return "primitive task" if t.primitive else "task"


def check_problem(domain: S.Domain, problem: S.Problem) -> list[Warning_]:
    """Raise :class:`HtnError` for tasks the problem asks that cannot exist."""
    warnings = []
    if problem.domain_name != domain.name:
        warnings.append(Warning_(problem.pos, f"problem is for domain '{problem.domain_name}' "
                                 f"but the domain is '{domain.name}'"))
    arities = _arities(domain)
    for inst in problem.instances:
        for t in S.task_atoms(inst.tasks):
            known = arities.get(t.name)
            if not known:
                kind = "operator" if t.primitive else "method"
                raise HtnError.at(t.pos, f"unknown {_describe_task(t)} '{t.name}': "
                                  f"the domain has no {kind} for it")
            if len(t.args) not in known:
                raise HtnError.at(t.pos, f"'{t.name}' takes {_plural(known)}, "
                                  f"given {len(t.args)}")
    return warnings


def _plural(arities: set[int]) -> str:
    ns = sorted(arities)
    words = " or ".join(str(n) for n in ns)
    return f"{words} argument" + ("" if ns == [1] else "s")


def check_domain(domain: S.Domain) -> list[Warning_]:
    """Arity errors inside the domain, and warnings for likely bugs."""
    warnings: list[Warning_] = []
    arities = _arities(domain)
    for ms in domain.methods.values():
        for m in ms:
            for b in m.branches:
                for t in S.task_atoms(b.tasks):
                    known = arities.get(t.name)
                    if not known:
                        warnings.append(Warning_(t.pos, f"{_describe_task(t)} '{t.name}' has no "
                                                 f"{'operator' if t.primitive else 'method'}; "
                                                 f"branch {b.label} of {m.name} can never succeed"))
                    elif len(t.args) not in known:
                        raise HtnError.at(t.pos, f"'{t.name}' takes {_plural(known)}, "
                                          f"given {len(t.args)}")
    for ops in domain.operators.values():
        for op in ops:
            warnings.extend(_unbound_effect_vars(op))
    return warnings


def _unbound_effect_vars(op: S.Operator) -> list[Warning_]:
    bound: set[str] = set()
    cb = lambda v: bound.add(v.name)  # noqa: E731
    _walk_term(op.head.args, cb)
    _walk_pre(op.pre, cb)
    found: dict[str, None] = {}
    for eff in (op.delete, op.add):
        for item in eff.items:
            if isinstance(item, S.EffectForAll):
                local: set[str] = set()
                _walk_expr(item.cond, lambda v: local.add(v.name))
                for a in item.atoms:
                    _walk_expr(a, lambda v: v.name in bound or v.name in local or found.setdefault(v.name))
            else:
                target = item.atom if isinstance(item, S.Protection) else item
                _walk_expr(target, lambda v: v.name in bound or found.setdefault(v.name))
        if eff.var is not None and eff.var.name not in bound:
            found.setdefault(eff.var.name)
    _walk_term(op.cost, lambda v: v.name in bound or found.setdefault(v.name))
    return [Warning_(op.pos, f"operator {op.name}: variable {name} in its effects or cost is "
                     "bound by neither its head nor its precondition")
            for name in found]
