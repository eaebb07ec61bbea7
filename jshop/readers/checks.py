"""Static checks of a domain and a problem: the one check that every command
reading them runs (``plan``, ``validate``, ``stats``, ``transform``, ``run``,
``evaluate``: :func:`check_inputs`), so the same input is accepted or refused
the same way everywhere, with the same located message.

Errors stop planning; warnings point at likely domain bugs but keep JSHOP2's
behaviour. Where JSHOP2 itself accepts the input we only warn: a task used in
a method body with no method or operator, or with an arity none of them has,
simply cannot be achieved there (manual 3.7 and 5.2.1: that branch never
applies; the JSHOP2 ``test`` example relies on it), and a variable a method
passes down unbound is how bindings fail to propagate upwards
(``propagation``).

Two errors go further than JSHOP2's compiler, because JSHOP2 would go wrong
later: a problem written for another domain (JSHOP2 compiles a problem against
the domain it names), and an add-list atom with a variable that neither the
operator's head nor its precondition binds (a state holds ground atoms only,
manual 5.1.2; such an atom would carry an unbound variable into the state).
"""

from __future__ import annotations

from collections import Counter

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.record import Record
from htn.jshop.language.terms import source_atom, variables
from htn.jshop.language.walk import walk_expr, walk_term


class Warning_(Record):
    __slots__ = ("pos", "message")

    def __init__(self, pos: S.Pos | None, message: str) -> None:
        self.pos, self.message = pos, message

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


def check_inputs(domain: S.Domain, problem: S.Problem) -> list[Warning_]:
    """The static check of a domain and a problem for it: raise
    :class:`HtnError` (located) for what no command can use, and return the
    located warnings (in the domain's order, then the problem's). A problem
    for another domain is refused first: nothing else about it is known."""
    check_domain_name(domain, problem)
    return check_domain(domain) + check_problem(domain, problem)


def check_problem(domain: S.Domain, problem: S.Problem) -> list[Warning_]:
    """Raise :class:`HtnError` for tasks the problem asks that cannot exist."""
    warnings: list[Warning_] = []
    check_domain_name(domain, problem)
    if problem.domain_name != domain.name:  # HDDL: see check_domain_name
        warnings.append(
            Warning_(
                problem.domain_pos or problem.pos,
                f"problem '{problem.name}' names domain "
                f"'{problem.domain_name}', not '{domain.name}'",
            )
        )
    arities = _arities(domain)
    for inst in problem.instances:
        for t in S.task_atoms(inst.tasks):
            known = arities.get(t.name)
            if not known:
                kind = "operator" if t.primitive else "method"
                raise HtnError.at(
                    t.pos,
                    f"unknown {_describe_task(t)} '{t.name}': the domain has no {kind} for it",
                )
            if len(t.args) not in known:
                raise HtnError.at(
                    t.pos,
                    f"'{t.name}' takes {_plural(known)}, "
                    f"given {len(t.args)}{_heads(domain, t.name)}",
                )
    for name, open_ in _open_positions(domain, problem).items():
        for op in domain.operators.get(name, ()):
            _unbound_effect_vars(op, open_)
    return warnings


def _heads(domain: S.Domain, name: str) -> str:
    """`` (it is (!brew ?robot ?cup) at coffee.jshop:8:14)``: the heads a
    task's arguments must match (the first two, if there are more)."""
    heads = [x.head for x in (*domain.operators.get(name, ()), *domain.methods.get(name, ()))]
    shown = {source_atom(h.name, h.args) + (f" at {h.pos}" if h.pos else ""): None for h in heads}
    text = " or ".join(list(shown)[:2]) + (" or ..." if len(shown) > 2 else "")
    return f" (it is {text})" if text else ""


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
                        warnings.append(
                            Warning_(
                                t.pos,
                                f"{_describe_task(t)} '{t.name}' has no "
                                f"{'operator' if t.primitive else 'method'}; "
                                f"branch {b.label} of {m.name} can never succeed",
                            )
                        )
                    elif len(t.args) not in known:
                        warnings.append(
                            Warning_(
                                t.pos,
                                f"'{t.name}' takes {_plural(known)}, "
                                f"given {len(t.args)}; branch {b.label} of "
                                f"{m.name} can never succeed"
                                f"{_heads(domain, t.name)}",
                            )
                        )
    elements = []
    for ops in domain.operators.values():
        for op in ops:
            warnings.extend(_unbound_effect_vars(op))
            elements.append(("operator", op.name, _operator_atoms(op)))
    for ms in domain.methods.values():
        elements.extend(("method", m.name, _method_atoms(m)) for m in ms)
    used = Counter(
        c
        for *_, atoms in elements
        for c in {a for x in atoms for a in x.args if isinstance(a, str)}
    )
    for kind, name, atoms in elements:
        warnings.extend(_constants_like_variables(kind, name, atoms, used))
    return warnings


def _expr_atoms(e, out: list) -> list:
    """The atoms of a logical expression, in textual order."""
    stack = [e]
    while stack:
        x = stack.pop()
        if isinstance(x, S.Atom):
            out.append(x)
        elif isinstance(x, (S.And, S.Or)):
            stack.extend(reversed(x.items))
        elif isinstance(x, S.Not):
            stack.append(x.expr)
        elif isinstance(x, S.ForAll):
            stack.extend((x.then, x.cond))
    return out


def _operator_atoms(op: S.Operator) -> list:
    out = [op.head]
    _expr_atoms(op.pre.expr, out)
    for eff in (op.delete, op.add):
        for item in eff.items:
            if isinstance(item, S.EffectForAll):
                _expr_atoms(item.cond, out)
                for a in item.atoms:
                    _expr_atoms(a, out)
            else:
                _expr_atoms(item.atom if isinstance(item, S.Protection) else item, out)
    return out


def predicate_arities(domain: S.Domain, problem: S.Problem | None = None) -> dict[str, set]:
    """The predicates the domain speaks of (in preconditions, effects and
    axioms; HDDL: its typing facts) and the problem's states, with the
    numbers of arguments each is written with: what a fact may be."""
    atoms: list = list(domain.facts)
    for op in (o for ops in domain.operators.values() for o in ops):
        atoms.extend(_operator_atoms(op)[1:])
    for m in (x for ms in domain.methods.values() for x in ms):
        for b in m.branches:
            _expr_atoms(b.pre.expr, atoms)
    for ax in (x for axs in domain.axioms.values() for x in axs):
        atoms.append(ax.head)
        for ab in ax.branches:
            _expr_atoms(ab.pre.expr, atoms)
    for inst in problem.instances if problem is not None else ():
        atoms.extend(inst.state)
    out: dict[str, set] = {}
    for a in atoms:
        if isinstance(a, S.Atom):
            out.setdefault(a.pred, set()).add(len(a.args))
    return out


def _method_atoms(m: S.Method) -> list:
    out = [m.head]
    for b in m.branches:
        _expr_atoms(b.pre.expr, out)
        out.extend(S.task_atoms(b.tasks))
    return out


def _constants_like_variables(kind: str, name: str, atoms: list, used: Counter) -> list[Warning_]:
    """A symbol ``cup`` where the same element has the variable ``?cup`` is
    most likely a variable written without its '?' (manual 3.1): legal, but
    it matches only the constant ``cup``. Not when the atom holds both (a
    type tag: ``(furniture ?table table)``) or other elements use the
    constant too (``used``: in how many elements each constant appears)."""
    names: set = set()
    for a in atoms:
        walk_term(a.args, lambda v: names.add(v.name))
    out, seen = [], set()
    for a in atoms:
        for arg in a.args:
            if (
                isinstance(arg, str)
                and f"?{arg}" in names
                and (id(a), arg) not in seen
                and used[arg] < 2
                and not any(getattr(x, "name", None) == f"?{arg}" for x in a.args)
            ):
                seen.add((id(a), arg))
                text = source_atom(getattr(a, "pred", None) or a.name, a.args)
                out.append(
                    Warning_(
                        a.pos,
                        f"{kind} {name}: '{arg}' in {text} is a constant, "
                        f"while ?{arg} is a variable of this {kind}; did you mean "
                        f"?{arg}? (variables start with '?', manual 3.1)",
                    )
                )
    return out


def _binds(e, out: set) -> set:
    """Add to ``out`` the names of the variables a satisfier of expression
    ``e`` binds to ground terms (manual 5.1.2), given those in ``out``: the
    variables of its positive atoms, and an assigned variable whose term's
    variables are bound. A negation, a forall and a call bind nothing; a
    disjunction counts what any disjunct binds."""
    assigns = []
    stack = [e]
    while stack:
        x = stack.pop()
        if isinstance(x, S.Atom):
            walk_term(x.args, lambda v: out.add(v.name))
        elif isinstance(x, (S.And, S.Or)):
            stack.extend(x.items)
        elif isinstance(x, S.Assign):
            assigns.append(x)
    while True:
        ready = [a for a in assigns if all(v.name in out for v in variables(a.term, []))]
        if not ready:
            return out
        out.update(a.var.name for a in ready)
        assigns = [a for a in assigns if a not in ready]


def _head_binds(head: S.TaskAtom, open_: dict) -> set:
    """Variables the head binds, except in the argument positions ``open_``
    (those a task may fill with a term that has unbound variables)."""
    out: set = set()
    for j, a in enumerate(head.args):
        if j not in open_:
            walk_term(a, lambda v: out.add(v.name))
    return out


def _unbound_effect_vars(op: S.Operator, open_: dict | None = None) -> list[Warning_]:
    """Warnings for effect and cost variables nothing binds; an error for
    such a variable in an add-list atom (it would enter the state unbound).
    ``open_`` maps head positions a task may leave unbound to where that task
    is written (see :func:`_open_positions`)."""
    open_ = open_ or {}
    bound = _binds(op.pre.expr, _head_binds(op.head, open_))
    found: dict[str, None] = {}
    for eff in (op.delete, op.add):
        for item in eff.items:
            if isinstance(item, S.EffectForAll):
                local = _binds(item.cond, bound | {v.name for v in item.vars})
                atoms, known = item.atoms, bound | local
            else:
                atoms, known = [item.atom if isinstance(item, S.Protection) else item], bound
            for a in atoms:
                free = [v.name for v in _vars_of(a) if v.name not in known]
                if (
                    free
                    and eff is op.add
                    and isinstance(a, S.Atom)
                    and not isinstance(item, S.Protection)
                ):
                    raise HtnError.at(
                        a.pos or op.pos,
                        f"operator {op.name} adds ({a.pred} ...) "
                        f"with {free[0]} unbound: {_why_unbound(op, free[0], open_)}"
                        ", and a state holds only ground atoms",
                    )
                for name in free:
                    found.setdefault(name)
        if eff.var is not None and eff.var.name not in bound:
            found.setdefault(eff.var.name)
    walk_term(op.cost, lambda v: v.name in bound or found.setdefault(v.name))
    return [
        Warning_(
            op.pos,
            f"operator {op.name}: variable {name} in its effects or cost is "
            "bound by neither its head nor its precondition",
        )
        for name in found
    ]


def _why_unbound(op: S.Operator, name: str, open_: dict) -> str:
    for j, a in enumerate(op.head.args):
        if j in open_ and any(v.name == name for v in variables(a, [])):
            return f"{open_[j].message} passes it unbound"
    return "neither its head nor its precondition binds it"


class _Source(Record):
    """A task (as written, and where) that may pass an unbound variable on."""

    __slots__ = ("task",)

    def __init__(self, task: S.TaskAtom) -> None:
        self.task = task

    @property
    def message(self) -> str:
        text = source_atom(self.task.name, self.task.args)
        return f"{text} at {self.task.pos}" if self.task.pos else text


def _open_positions(domain: S.Domain, problem: S.Problem) -> dict[str, dict[int, _Source]]:
    """For each task name, the argument positions a task may fill with a term
    that has unbound variables (a variable of the problem, or one a method
    neither receives bound nor binds in its precondition), found by
    following method bodies to a fixed point."""
    open_: dict[str, dict[int, _Source]] = {}
    todo = list(domain.methods)

    def mark(t: S.TaskAtom, bound: set | None) -> None:
        for j, arg in enumerate(t.args):
            names = {v.name for v in variables(arg, [])}
            if (
                names
                and (bound is None or not names <= bound)
                and j not in open_.setdefault(t.name, {})
            ):
                open_[t.name][j] = _Source(t)
                todo.append(t.name)

    for inst in problem.instances:
        for t in S.task_atoms(inst.tasks):
            mark(t, None)
    while todo:
        for m in domain.methods.get(todo.pop(), ()):
            head = _head_binds(m.head, open_.get(m.name, {}))
            for b in m.branches:
                bound = _binds(b.pre.expr, set(head))
                for t in S.task_atoms(b.tasks):
                    mark(t, bound)
    return open_


def _vars_of(a) -> list:
    out: list = []
    walk_expr(a, out.append)
    return out


def compat_warning(domain: S.Domain):
    """The one warning ``--jshop2-compat`` gives for a domain whose method
    bodies are written ``(:unordered ...)`` (they will run in order), or None."""
    bodies = [
        b for ms in domain.methods.values() for m in ms for b in m.branches if not b.tasks.ordered
    ]
    if not bodies:
        return None
    more = f" (and {len(bodies) - 1} more)" if len(bodies) > 1 else ""
    return Warning_(
        bodies[0].tasks.pos or bodies[0].pos,
        f"--jshop2-compat: this (:unordered ...) method body{more} runs in "
        "order, as in JSHOP2 1.0.3; without the option it is unordered",
    )


def check_domain_name(domain: S.Domain, problem: S.Problem) -> None:
    """A problem names its domain (manual 3.12) and JSHOP2 compiles it against
    that domain only: another domain's problem is an error at the name. An
    HDDL problem may name another domain (a warning): the IPC 2020 planners
    do not compare the names, and Barman-BDI's problems name ``barman_htn``
    while its domain is ``barman_agent``."""
    if problem.domain_name != domain.name and domain.language != "hddl":
        raise HtnError.at(
            problem.domain_pos or problem.pos,
            f"problem '{problem.name}' is for domain '{problem.domain_name}', "
            f"but {domain.file or 'the domain'} defines '{domain.name}'",
        )
