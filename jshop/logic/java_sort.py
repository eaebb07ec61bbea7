"""Java 17's ``Arrays.sort(Object[], Comparator)``, with which JSHOP2 sorts
the satisfiers of a ``:sort-by`` precondition (manual 3.6), and that sort."""

from __future__ import annotations

from functools import cmp_to_key

from htn.jshop.language.errors import HtnError, PlanningError
from htn.jshop.language.terms import shown_term


def java_sort(a: list, cmp) -> list:
    """Sort like Java 17's ``Arrays.sort(Object[], Comparator)``.

    JSHOP2 sorts ``:sort-by`` bindings with it. For fewer than 32 elements Java's
    TimSort is a binary insertion sort after one run scan; that is ported here
    step by step, because with an inconsistent comparator (the corpus's
    MyComparator) only the exact algorithm gives JSHOP2's order. Longer inputs
    use Python's stable TimSort, which agrees with Java for every consistent
    comparator.
    """
    n = len(a)
    if n < 2:
        return a
    if n >= 32:
        return sorted(a, key=cmp_to_key(cmp))
    run = 1
    if cmp(a[1], a[0]) < 0:
        run = 2
        while run < n and cmp(a[run], a[run - 1]) < 0:
            run += 1
        a[:run] = a[:run][::-1]
    else:
        run = 2
        while run < n and cmp(a[run], a[run - 1]) >= 0:
            run += 1
    for start in range(run, n):
        pivot = a[start]
        left, right = 0, start
        while left < right:
            mid = (left + right) >> 1
            if cmp(pivot, a[mid]) < 0:
                right = mid
            else:
                left = mid + 1
        a[left + 1 : start + 1] = a[left:start]
        a[left] = pivot
    return a


def sorted_by(sat, pre, functions):
    """The satisfiers of ``sat`` sorted as a ``:sort-by`` precondition ``pre``
    says (manual 3.5): by its variable's value with ``<`` or ``>`` (numbers
    only), or with a user comparator from ``functions``."""
    idx = pre.sort_var.index
    name = pre.comparator
    if name in ("<", ">"):
        sign = 1 if name == "<" else -1

        def cmp(a, b):
            x, y = a[idx], b[idx]
            if type(x) is not float or type(y) is not float:
                raise PlanningError.at(
                    pre.pos,
                    f":sort-by {name} needs numbers, got {shown_term(x)} and {shown_term(y)}",
                )
            return sign * ((x > y) - (x < y))
    else:
        from htn.jshop.language.functions import compare

        user = functions.comparator(name) if functions else None
        if user is None:
            raise HtnError.at(pre.pos, f"undefined comparator '{name}'")

        def cmp(a, b):
            try:
                return compare(name, user, a[idx], b[idx], functions.guard)
            except HtnError as exc:  # placed at the :sort-by that called it
                raise PlanningError.at(pre.pos, exc.message) from None

    def sorted_sat(env):
        yield from java_sort(list(sat(env)), cmp)

    return sorted_sat
