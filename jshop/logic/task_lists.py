"""Method bodies bound by generated code: one function per task list of the
domain, which substitutes a binding into its task atoms inline (the search
binds a method body each time it reduces a task with it)."""

from __future__ import annotations

from collections.abc import Callable

from htn.jshop.language.terms import Var, source_atom

from .caches import cache
from .codegen import define, described
from .compile import flat_args, substituter
from .warming import interpreted_substitution, warming

_TASK_LISTS = cache()


def task_list_maker(
    tl, node: Callable, task: Callable, what: str = "task list"
) -> Callable[[list], list]:
    """``env -> [node]``: the members of a domain's task list bound by
    ``env``, one function of generated code per list: a task atom becomes
    ``node(task(name, args, immediate, atom))`` with its arguments substituted
    inline (as :func:`substituter` does), a nested list ``node(None, members,
    ordered)`` (its own function, so the code never nests). Cached per list
    object and node and task constructors. ``what`` names the generated
    code (``subtasks of m_deliver``, see :mod:`~htn.jshop.logic.codegen`)."""
    # the constructors are part of the key (kept alive by it)
    make = _TASK_LISTS.get(tl, (id(tl), node, task))
    if make is None:
        ns: dict = {"N": node, "T": task}
        parts = []
        for i, x in enumerate(tl.items):
            if hasattr(x, "items"):  # a nested task list
                ns[f"m{i}"] = task_list_maker(x, node, task, f"{what}, nested list {i + 1}")
                parts.append(f"N(None, m{i}(env), {bool(x.ordered)})")
                continue
            ns[f"a{i}"], ns[f"n{i}"] = x, x.name
            if flat_args(x.args):
                args = []
                for j, a in enumerate(x.args):
                    ns[f"c{i}_{j}"] = a
                    args.append(
                        f"(env[{a.index}] if env[{a.index}] is not None else c{i}_{j})"
                        if type(a) is Var
                        else f"c{i}_{j}"
                    )
                bound = "(" + "".join(a + ", " for a in args) + ")"
            else:
                ns[f"s{i}"] = substituter(
                    x.args,
                    described(f"arguments of the subtask {source_atom(x.name, x.args)}", x.pos),
                )
                bound = f"s{i}(env)"
            parts.append(f"N(T(n{i}, {bound}, {bool(x.immediate)}, a{i}))")
        src = "def make(env):\n    return [" + "".join(p + ",\n        " for p in parts) + "]"
        define(src, described(what, tl.pos), ns)
        make = _TASK_LISTS.put(tl, ns["make"], (id(tl), node, task))
    return make


def task_list_warming(
    tl, node: Callable, task: Callable, what: str, install: Callable
) -> Callable[[list], list]:
    """:func:`task_list_maker`, warming (see :mod:`~htn.jshop.logic.warming`):
    the members are first built term by term, with ``subst``."""
    made = _TASK_LISTS.get(tl, (id(tl), node, task))
    if made is not None:
        return made
    return warming(
        _interpreted(tl, node, task),
        lambda: task_list_maker(tl, node, task, what),
        install,
        tl,
        node,
    )


def _interpreted(tl, node: Callable, task: Callable) -> Callable[[list], list]:
    members = [
        (None, _interpreted(x, node, task), bool(x.ordered))
        if hasattr(x, "items")
        else (x, interpreted_substitution(x.args), bool(x.immediate))
        for x in tl.items
    ]

    def make(env):
        return [
            node(None, inner(env), flag) if x is None else node(task(x.name, inner(env), flag, x))
            for x, inner, flag in members
        ]

    return make
