"""Matching a pattern against the atoms of one predicate, in the state's order."""

from __future__ import annotations

from collections.abc import Iterator

from htn.jshop.language.terms import Var, unify


def scan_atoms(lst: list, bound: tuple, env: list) -> Iterator[list]:
    """Match a non-ground pattern against a live list of atoms, in order.

    Iterating the live list by index is deliberate: it reproduces JSHOP2's
    behaviour when a forall effect deletes atoms while it enumerates them.
    """
    n = len(bound)
    consts = []
    binds = []
    others = []
    seen = set()
    i = 0
    for t in bound:
        tt = type(t)
        if tt is str or tt is float:
            consts.append((i, t))
        elif tt is Var and t.index not in seen:
            seen.add(t.index)
            binds.append((i, t.index))
        else:
            others.append((i, t))
        i += 1
    if not others and len(consts) == 1:
        ((ci, c),) = consts
        for args in lst:
            if len(args) == n and args[ci] == c:
                new = env[:]
                for i, k in binds:
                    new[k] = args[i]
                yield new
        return
    if not others and not consts:
        for args in lst:
            if len(args) == n:
                new = env[:]
                for i, k in binds:
                    new[k] = args[i]
                yield new
        return
    for args in lst:
        if len(args) != n:
            continue
        for i, c in consts:
            if args[i] != c:
                break
        else:
            new = env[:]
            for i, k in binds:
                new[k] = args[i]
            if others:
                ok = True
                for i, t in others:
                    if not unify(t, args[i], new):
                        ok = False
                        break
                if not ok:
                    continue
            yield new
