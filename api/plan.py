"""The plan use case: the plans of a problem, with their task trees and the
search's statistics, and why there is no plan (``htn plan``).

:func:`plan` reads and checks the inputs at once (an input error is raised
there, with its ``file:line:col``) and returns a :class:`PlanStream`; the
search runs as the stream is iterated, one plan at a time, so a program (or
``htn plan --all``) holds one plan at a time however many there are. The
planner follows the JSHOP2 manual, sections 4 and 5 (:mod:`htn.jshop.search.planner`).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import FunctionTable, Guard
from htn.jshop.language.terms import java_double
from htn.jshop.plans.plan import Plan
from htn.jshop.readers.checks import compat_warning
from htn.jshop.search.limits import DEFAULT_MAX_DEPTH
from htn.jshop.search.searches import SEARCHES, make_search, refusal
from htn.jshop.search.stream import SearchStream

from .inputs import function_table, path_of, read_inputs

if TYPE_CHECKING:
    from htn.jshop.checks.explain import Explainer
    from htn.jshop.search.searches import Search

    from .inputs import DomainInput, FunctionsInput, ProblemInput

# what the command line shows of plans and searches (it imports only htn.api)
__all__ = [
    "plan",
    "PlanStream",
    "UnsupportedSearch",
    "ipc_text",
    "java_double",
    "SEARCHES",
    "DEFAULT_MAX_DEPTH",
]

# seconds the explanation of "no plan" may take at least (see PlanStream.explain)
EXPLAIN_MIN = 1.0


def plan(
    domain: DomainInput,
    problem: ProblemInput,
    *,
    plans: int | None = 1,
    timeout: float | None = None,
    functions: FunctionsInput = None,
    jshop2_compat: bool = False,
    max_depth: int = DEFAULT_MAX_DEPTH,
    max_memory: int | None = None,
    explain: bool = False,
    explain_all: bool = False,
    trees: bool = True,
    tree_paths: bool = True,
    search: str = "dfs",
    stops: Guard | None = None,
) -> PlanStream:
    """The plans of ``problem`` in ``domain`` (paths or loaded objects, see
    :mod:`htn.api.inputs`), as a stream in JSHOP2's order.

    ``plans``: at most this many per problem instance (None: every plan,
    JSHOP2's ``-ra``). ``timeout``: seconds of wall clock from this call
    (reading included) after which the search stops, keeping what it found;
    the planner checks it between expansions (the command line also stops a
    user function that never returns). ``functions``: a Python file or a
    :class:`~htn.jshop.language.functions.FunctionTable` for ``(call ...)``.
    ``jshop2_compat``: run ``(:unordered ...)`` method bodies in order, as
    JSHOP2 1.0.3 does. ``max_depth``: nested method reductions without an
    operator in between before the search stops; ``max_memory``: megabytes
    of resident memory (None: 80% of what is available). ``explain``
    records the search's dead ends (``explain_all``: every one, not only the
    deepest; see :meth:`PlanStream.explain`). ``trees``: record each plan's
    task tree (``Plan.tree``); ``tree_paths``: with node paths. ``search``:
    one of :data:`htn.jshop.search.searches.SEARCHES` (``dfs``, the default,
    is JSHOP2's depth-first search; the others find plans one at a time, on
    HDDL and on JSHOP2 input that can be grounded, see
    :mod:`htn.jshop.search.jshop2_input`; :class:`UnsupportedSearch`
    otherwise, where ``auto`` runs depth-first search alone). ``stops``: the
    command's :class:`htn.process.Stops` (the user functions run under them).
    """
    started = time.perf_counter()
    table = function_table(functions, stops)
    inputs = read_inputs(domain, problem, table)
    dom, prob, warnings = inputs.domain, inputs.problem, list(inputs.warnings)
    why = refusal(search, dom, plans is None, prob, jshop2_compat)
    if why:
        raise UnsupportedSearch(why)
    if jshop2_compat:
        warnings += [str(w) for w in filter(None, [compat_warning(dom)])]
    options: dict[str, Any] = dict(
        jshop2_compat=jshop2_compat,
        max_depth=max_depth,
        max_memory=max_memory << 20 if max_memory else None,
    )
    return PlanStream(
        dom,
        prob,
        table,
        warnings,
        options,
        started,
        timeout,
        plans,
        explain or explain_all,
        explain_all,
        trees,
        tree_paths,
        search,
    )


def ipc_text(plan: Plan, spelling: dict[str, str] | None = None) -> str:
    """``plan`` in the IPC 2020 HTN plan format (actions and decompositions);
    ``spelling``: names as the input wrote them."""
    from htn.jshop.plans.ipc import ipc_text as text

    return text(plan, spelling or {})


class UnsupportedSearch(HtnError):
    """The search asked for cannot run on this input (``--search gbfs`` on
    JSHOP2 input that cannot be grounded, with ``--jshop2-compat``, or with
    every plan asked for)."""


class PlanStream:
    """The plans of every instance of a problem (a ``defproblem`` may hold
    several), streamed by iterating (once). Each plan is a
    :class:`~htn.jshop.plans.plan.Plan` with ``instance`` (the instance's
    0-based index), ``index`` (its place in that instance's stream) and,
    when recorded, ``tree``.

    ``domain``, ``problem`` and ``functions`` are the inputs as read (pass
    them on to :func:`htn.run`); ``warnings`` the domain's and problem's
    located warnings; ``stats`` the statistics so far (final once the stream
    ends or is closed); ``bound`` the message of the bound (``max_depth``,
    ``max_memory``) that stopped the search, if one did.
    """

    def __init__(
        self,
        domain: S.Domain,
        problem: S.Problem,
        functions: FunctionTable,
        warnings: list[str],
        options: dict[str, Any],
        started: float,
        timeout: float | None,
        limit: int | None,
        explain: bool,
        explain_all: bool,
        trees: bool,
        tree_paths: bool,
        search: str = "dfs",
    ) -> None:
        self.domain, self.problem, self.functions = domain, problem, functions
        self.warnings: list[str] = warnings
        self.options = options
        self.started, self.timeout, self.limit = started, timeout, limit
        self.explain_all = explain_all
        self.record = explain
        self.trees, self.tree_paths = trees, tree_paths
        self.explanations: list[
            Explainer
        ] = []  # one Explainer per instance searched (explain=True)
        self.search = search  # its name (see plan())
        self._plans = SearchStream(
            problem.instances, self._make, started=started, timeout=timeout, limit=limit
        )
        self.stats = self._plans.stats

    @property
    def bound(self) -> str | None:
        bound = self._plans.bound
        return None if bound is None else str(bound)

    @property
    def domain_file(self) -> str | None:
        return path_of(self.domain)

    @property
    def problem_file(self) -> str | None:
        return path_of(self.problem)

    def __iter__(self) -> Iterator[Plan]:
        return iter(self._plans)

    def __next__(self) -> Plan:
        return next(self._plans)

    def close(self) -> None:
        """End the search now (its statistics are then final)."""
        self._plans.close()

    def __enter__(self) -> PlanStream:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _make(self, k: int, instance: object) -> Search:
        explainer = None
        if self.record:
            from htn.jshop.checks.explain import Explainer

            explainer = Explainer(keep_all=self.explain_all)
            self.explanations.append(explainer)
        return make_search(
            self.search,
            self.domain,
            instance,
            self.functions,
            record_trees=self.trees,
            tree_paths=self.tree_paths,
            explain=explainer,
            **self.options,
        )

    def explain(self) -> list[Explainer]:
        """Why the search found what it found: one
        :class:`~htn.jshop.checks.explain.Explainer` per problem instance, its
        dead ends with the precondition literal that failed and its
        ``file:line:col``. Without ``explain=True`` the search is run again,
        recording them this time (planning without it pays nothing for them)."""
        if not self.explanations:
            from htn.jshop.checks.explain import explain_search

            left = None  # what is left of ``timeout``, which bounds the explanation too
            spent = time.perf_counter() - self.started
            if self.timeout is not None:
                left = max(0.0, self.timeout - spent)
            # asked for after the answer, it takes no longer than the search did (at
            # least a second): a grounded search can prove in 16 s that a problem has
            # no plan where depth-first search runs on (IPC 2020 Minecraft-Player)
            budget = max(EXPLAIN_MIN, spent)
            bounded = left is None or budget < left  # the budget, not --timeout, bounds it
            left = budget if left is None else min(left, budget)
            self.explanations = [
                explain_search(
                    self.domain,
                    inst,
                    self.functions,
                    keep_all=self.explain_all,
                    timeout=left,
                    **self.options,
                )
                for inst in self.problem.instances
            ]
            if bounded:
                for e in self.explanations:
                    e.after = budget if e.cut_short else None
        return self.explanations
