"""How a decomposition line of an IPC plan instantiates an HDDL method.

A line ``id task args -> method ids`` applies the method (HDDL, Höller et
al., AAAI 2020; the IPC 2020 verifier, pandaPIparser's ``--verify``) when
the method decomposes that task and its ``:task`` arguments unify with the
line's, and the listed ids are the method's subtasks, each exactly once, in
an order that the method's ordering allows (no listed subtask comes after
one it must precede), with the same names and arguments under one binding
of the method's variables; every bound variable must be an object of its
type. The variables that neither the task nor the subtasks bind are
existentially quantified in the method's precondition, which is tested
later, in the state where the method is applied
(:mod:`htn.jshop.checks.ipc_verify`).

The problem's initial task network is the method ``__top_method`` of the
artificial task ``__top`` (as the verifier and the IPC plan format have
it), with the network's ``:parameters`` as its variables and its
``:constraints`` as its precondition.

Unlike the verifier, a line must list all of its method's subtasks: the
verifier stops matching when every listed id is matched, so a line that
leaves out a subtask whose actions have no effect can pass there.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.terms import Var, term_str, variables
from htn.jshop.readers.hddl_formulas import Formulas, Scope, order_conjuncts, type_condition
from htn.jshop.readers.hddl_model import TOP, TOP_METHOD, HDomain


@dataclass
class Shape:
    """What a method requires of a decomposition line, in the method's
    variables (numbered as JSHOP2's binding array)."""

    name: str
    task: str
    head: tuple  # the :task arguments (terms)
    subtasks: list  # [(name, terms, label)]
    pairs: list  # [(i, j)]: subtask i before subtask j
    preds: list  # preds[j]: the i of the pairs (i, j)
    params: list  # [(Var, types)]
    pre: S.Precondition  # written precondition, :constraints, parameter types
    bound: tuple  # the variables the head and the subtasks bind
    nvars: int
    pos: S.Pos | None = None


@dataclass
class Match:
    """One way a line's ids are the method's subtasks: ``order[k]`` is the
    method's subtask of the k-th listed id; ``env`` the binding."""

    order: tuple
    env: list


@dataclass
class Mismatch:
    """Why a line does not instantiate its method: the message, and the
    position in the line's id list it is about (None: the line itself)."""

    message: str
    at: int | None = None
    depth: int = -1


def shape(m, predicates: dict) -> Shape:
    """The :class:`Shape` of an HDDL method (:class:`~htn.jshop.readers.hddl_model.MethodDef`)."""
    scope = Scope()
    names = {p.name: p.name for p in m.params}
    params = [scope.var(p.name) for p in m.params]
    f = Formulas(scope, predicates)
    f.outer.update(v.index for v in params)
    head = tuple(f.term(x, names, m.task.pos) for x in m.task.args)
    net = m.network
    subs = [
        (st.name, tuple(f.term(x, names, st.pos) for x in st.args), st.label)
        for st in (net.subtasks if net is not None else [])
    ]
    conds, types = f.conjuncts(m.pre, names)
    more, more_types = f.conjuncts(net.constraints if net is not None else None, names)
    conds += more
    types += more_types + [type_condition(v, p.types, p.pos) for v, p in zip(params, m.params)]
    bound = set()
    for term in (head, *(s[1] for s in subs)):
        bound |= {v.index for v in variables(term, [])}
    items = order_conjuncts(conds, types, bound, f.outer)
    pairs = _pairs(net, subs, m.name)
    preds: list = [set() for _ in subs]
    for i, j in pairs:
        preds[j].add(i)
    bound_vars = tuple(scope.var(n) for n, i in scope.slots.items() if i in bound)
    return Shape(
        m.name,
        m.task.name,
        head,
        subs,
        pairs,
        preds,
        list(zip(params, (p.types for p in m.params))),
        S.Precondition(S.And(items), pos=m.pos),
        bound_vars,
        scope.size,
        m.pos,
    )


def top_shape(problem_model, predicates: dict) -> Shape:
    """The problem's initial task network as the method ``__top_method``."""
    from htn.jshop.readers.hddl_model import MethodDef, Network, Subtask

    net = problem_model.network or Network()
    top = MethodDef(
        TOP_METHOD,
        problem_model.params,
        Subtask(None, TOP, (), problem_model.pos),
        None,
        net,
        problem_model.pos,
    )
    return shape(top, predicates)


def _pairs(net, subs: list, owner: str) -> list:
    """The method's ordering as pairs of subtask indices (HDDL: ``:ordered-
    subtasks`` is a chain; ``:subtasks`` are ordered by ``:ordering`` only)."""
    if net is None or len(subs) < 2:
        return []
    if net.ordered:
        return [(i, i + 1) for i in range(len(subs) - 1)]
    index = {label: i for i, (_, _, label) in enumerate(subs) if label is not None}
    out = []
    for a, b, pos in net.ordering:
        for x in (a, b):
            if x not in index:
                raise HtnError.at(pos, f"method {owner}: no subtask is labelled {x}")
        out.append((index[a], index[b]))
    return out


def matchings(sh: Shape, args: tuple, children: list, of_type, limit: int = 64):
    """The ways a line with task arguments ``args`` and listed subtasks
    ``children`` ([(name, args)]) instantiates the method (at most
    ``limit``), and, when there is none, the :class:`Mismatch` that says why.
    ``of_type(obj, types)`` tells whether an object has one of the types."""
    env: list = [None] * sh.nvars
    for k, (term, value) in enumerate(zip(sh.head, args)):
        clash = _bind(term, value, env)
        if clash:
            return [], Mismatch(
                f"argument {k + 1} of the task is {value}, but method "
                f"{sh.name} decomposes ({sh.task} "
                f"{' '.join(_term(t) for t in sh.head)}){clash}"
            )
    if len(children) != len(sh.subtasks):
        return [], Mismatch(
            f"method {sh.name} has {len(sh.subtasks)} subtask(s), the line lists {len(children)}"
        )
    found: list = []
    worst = Mismatch("", None, -1)

    def search(k: int, done: tuple, env: list) -> None:
        nonlocal worst
        if len(found) >= limit:
            return
        if k == len(children):
            bad = _untyped(sh, env, of_type)
            if bad:
                if k >= worst.depth:
                    worst = Mismatch(bad, None, k)
                return
            found.append(Match(done, env))
            return
        name, values = children[k]
        tried = []
        for i, (sub, terms, label) in enumerate(sh.subtasks):
            if i in done or not sh.preds[i] <= set(done):
                continue
            if sub != name:
                tried.append(_show_sub(sub, terms, label))
                continue
            new = list(env)
            clash = next(filter(None, (_bind(t, v, new) for t, v in zip(terms, values))), "")
            if clash:
                tried.append(_show_sub(sub, terms, label) + clash)
                continue
            search(k + 1, done + (i,), new)
        if not found and k >= worst.depth:
            allowed = "; ".join(tried) if tried else "none"
            worst = Mismatch(
                f"({' '.join((name, *values))}) is not a subtask of method "
                f"{sh.name} that may come here (allowed: {allowed})",
                k,
                k,
            )

    search(0, (), env)
    return found, (None if found else worst)


def _bind(term, value: str, env: list) -> str:
    """Unify a method term with a plan argument in ``env``: '' on success,
    else a note on the clash."""
    if type(term) is Var:
        old = env[term.index]
        if old is None:
            env[term.index] = value
            return ""
        return "" if old == value else f" ({term.name} is already {old})"
    return "" if term_str(term) == value else f" ({term_str(term)} is not {value})"


def _untyped(sh: Shape, env: list, of_type) -> str:
    for v, types in sh.params:
        value = env[v.index]
        if value is not None and not of_type(value, types):
            kinds = " or ".join(types)
            return f"method {sh.name}: {v.name} = {value}, which is not of type {kinds}"
    return ""


def _term(t) -> str:
    return t.name if type(t) is Var else term_str(t)


def _show_sub(name: str, terms: tuple, label) -> str:
    text = "(" + " ".join((name, *(_term(t) for t in terms))) + ")"
    return f"{label} {text}" if label else text


@dataclass
class Shapes:
    """The shapes of a domain's methods, made when first asked."""

    model: HDomain
    cache: dict = field(default_factory=dict)

    def get(self, task: str, name: str):
        """The shape of method ``name`` of ``task``, or (None, why not)."""
        hit = self.cache.get((task, name))
        if hit is not None:
            return hit, ""
        ms = [m for m in self.model.methods if m.name == name]
        m = next((m for m in ms if m.task.name == task), None)
        if m is None:
            if ms:
                return None, f"method {name} decomposes {ms[0].task.name}, not {task}"
            return None, f"the domain has no method {name}"
        hit = self.cache[(task, name)] = shape(m, self.model.predicates)
        return hit, ""
