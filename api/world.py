"""The world model of a long-lived planner (the knowledge base of a robot
node): the facts believed now, from which the next goal is planned.

It starts from a problem's initial state (or empty) and is updated by what
a run verified (the executor's belief after it), by what the robot
observes, and by facts other programs report (:meth:`WorldModel.update`,
each fact checked against the predicates the domain speaks of). A goal is
a task list in the domain's syntax, ``((bring_object jenny pringles guest))``;
it becomes a problem with the current facts as its state
(:meth:`WorldModel.problem`), read and checked as a problem file is, its
errors located in the goal's text (``goal:1:3: unknown task ...``).

JSHOP2 domains only, for now: an HDDL goal needs the objects' types, which
an HDDL problem declares and a bare task list does not.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any, TypeVar, cast

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import Guard
from htn.jshop.language.terms import source_atom
from htn.jshop.readers.checks import check_problem, predicate_arities
from htn.jshop.readers.load import load_domain, load_problem, parse_text
from htn.jshop.readers.parens import first_unmatched_close, open_lists
from htn.jshop.readers.source import check_nesting, position

from .inputs import function_table, is_path

if TYPE_CHECKING:
    from .inputs import DomainInput, FunctionsInput, ProblemInput
    from .plan import PlanStream

T = TypeVar("T")
# a fact as a run or a robot reports it: (pred, args)
Fact = tuple[str, Iterable[Any]]


class WorldModel:
    """The facts believed now, for ``domain`` (a path or a loaded domain);
    ``problem`` (a path or a loaded problem, optional) gives the first
    state. Safe to use from several threads (a node's callbacks)."""

    def __init__(
        self,
        domain: DomainInput,
        problem: ProblemInput | None = None,
        functions: FunctionsInput = None,
        stops: Guard | None = None,
    ) -> None:
        self.functions = function_table(functions, stops)
        self.domain: S.Domain = (
            load_domain(os.fspath(domain), self.functions)
            if is_path(domain)
            else cast(S.Domain, domain)
        )
        if self.domain.language != "jshop2":
            raise HtnError(
                "a world model plans goals for JSHOP2 domains only (an HDDL goal "
                "needs its objects' types)",
                self.domain.file or None,
            )
        prob: S.Problem | None = None
        if problem is not None:
            prob = (
                load_problem(os.fspath(problem), self.functions)
                if is_path(problem)
                else cast(S.Problem, problem)
            )
            check_problem(self.domain, prob)
        self.arities = predicate_arities(self.domain, prob)
        self._lock = threading.Lock()
        self._facts: dict[tuple[str, tuple[Any, ...]], S.Atom] = {}
        # (deleted, added) atoms of each update()
        self._updates: list[tuple[list[S.Atom], list[S.Atom]]] = []
        self._forgotten = 0  # updates dropped from the list, settled
        for atom in prob.instances[0].state if prob is not None else ():
            self._facts[(atom.pred, atom.args)] = atom

    # ------------------------------------------------------------ reading
    def facts(self) -> list[str]:
        """Every fact believed now, as source text, in the order learnt."""
        with self._lock:
            return [source_atom(a.pred, a.args) for a in self._facts.values()]

    def atoms(self) -> list[S.Atom]:
        with self._lock:
            return list(self._facts.values())

    def query(self, pattern: str = "") -> list[str]:
        """The facts that match ``pattern``, an atom whose ``?variables``
        match anything (the same variable the same thing); empty: all."""
        if not pattern.strip():
            return self.facts()
        pred, args = _pattern(pattern)
        return [
            source_atom(a.pred, a.args)
            for a in self.atoms()
            if a.pred == pred and _matches(args, a.args)
        ]

    # ------------------------------------------------------------ changing
    def update(
        self, add: Iterable[str] = (), delete: Iterable[str] = (), source: str = "facts"
    ) -> int:
        """Delete, then add, the facts given as source text (``(at robby
        kitchen)``); every one is checked first (syntax, ground, a predicate
        the domain speaks of, with the number of arguments it has there), so
        that a bad one changes nothing. ``source`` names them in errors.
        Returns how many facts are believed after."""
        gone = [a for text in delete for a in self._parse_atoms(text, source)]
        new = [a for text in add for a in self._parse_atoms(text, source)]
        with self._lock:
            self._apply(gone, new)
            self._updates.append((gone, new))
            return len(self._facts)

    def _apply(self, gone: Iterable[S.Atom], new: Iterable[S.Atom]) -> None:
        for a in gone:
            self._facts.pop((a.pred, a.args), None)
        for a in new:
            self._facts[(a.pred, a.args)] = a

    def mark(self) -> int:
        """Where the updates from other programs stand now (see :meth:`believe`)."""
        with self._lock:
            return self._forgotten + len(self._updates)

    def believe(self, facts: Iterable[Fact], since: int | None = None) -> None:
        """The facts are now these ``(pred, args)`` pairs (what a run
        verified: the executor's belief state when it ended), with the
        updates other programs made after the :meth:`mark` ``since`` applied
        again on top (what they reported while the run went on is not lost)."""
        atoms = {(p, tuple(args)): S.Atom(p, tuple(args)) for p, args in facts}
        with self._lock:
            self._facts = atoms
            if since is not None:
                for gone, new in self._updates[max(0, since - self._forgotten) :]:
                    self._apply(gone, new)
            # one run at a time: the updates before now are in the facts for good
            self._forgotten += len(self._updates)
            self._updates.clear()

    def observed(self, facts: Iterable[Fact]) -> None:
        """The robot observed ``facts`` (``(pred, args)`` pairs, every fact
        of the domain's dynamic predicates it perceives): they replace the
        believed facts of those predicates; the static facts stay (as
        repair builds its state, :func:`htn.executor.repair.observed_instance`)."""
        dynamic = self.domain.dynamic_predicates()
        seen = [S.Atom(p, tuple(args)) for p, args in facts]
        with self._lock:
            kept = {k: a for k, a in self._facts.items() if a.pred not in dynamic}
            kept.update(((a.pred, a.args), a) for a in seen)
            self._facts = kept

    # ------------------------------------------------------------ goals
    def problem(self, tasks: str, source: str = "goal") -> S.Problem:
        """A problem whose state is the facts believed now and whose task
        list is ``tasks`` (JSHOP2 syntax), read and checked as a problem
        file is; errors are located in ``tasks`` (``goal:1:col``)."""
        if not tasks.strip():
            raise HtnError("the goal has no tasks", source, 1, 1)
        _balanced(tasks, source)
        # the task list on line 2 of a problem text: its errors say line 2
        text = f"(defproblem {source} {self.domain.name} ()\n{tasks}\n)"
        prob = _on_first_line(lambda: parse_text(text, source, self.functions, "problem"), source)
        if not isinstance(prob, S.Problem) or len(prob.instances) != 1:
            raise HtnError(
                "a goal is one task list, e.g. ((bring_object jenny pringles guest))", source, 1, 1
            )
        prob.instances[0].state = self.atoms()
        _on_first_line(lambda: check_problem(self.domain, prob), source)
        return prob

    def _parse_atoms(self, text: str, source: str) -> list[S.Atom]:
        """The atoms of ``text`` (one or more), checked against the domain."""
        _balanced(text, source)
        prob = _on_first_line(
            lambda: parse_text(
                f"(defproblem {source} {self.domain.name} (\n{text}\n) ())",
                source,
                self.functions,
                "problem",
            ),
            source,
        )
        atoms = prob.instances[0].state if isinstance(prob, S.Problem) else []
        if not atoms:
            raise HtnError(f"no fact in {text!r}", source, 1, 1)
        for a in atoms:
            where = (source, a.pos.line - 1, a.pos.col) if a.pos else (source,)
            known = self.arities.get(a.pred)
            if known is None:
                raise HtnError(
                    f"unknown predicate '{a.pred}': the domain "
                    f"'{self.domain.name}' never speaks of it",
                    *where,
                )
            if len(a.args) not in known:
                raise HtnError(
                    f"'{a.pred}' has {' or '.join(map(str, sorted(known)))} "
                    f"argument(s) in the domain, given {len(a.args)}",
                    *where,
                )
        return atoms


def _balanced(text: str, source: str) -> None:
    """Refuse unbalanced parentheses in the caller's own text (wrapped in a
    problem, the reader would blame the wrapper's)."""
    check_nesting(text, source)
    still_open = open_lists(text, len(text))
    if still_open:
        first = still_open[-1]
        raise HtnError("this '(' is never closed", source, first.line, first.col)
    extra = first_unmatched_close(text)
    if extra is not None:
        raise HtnError("this ')' closes nothing", source, *position(text, extra))


def _on_first_line(read: Callable[[], T], source: str) -> T:
    """``read()``, its errors in the text on line 2 of a wrapper said on
    line 1 (the text the caller gave)."""
    try:
        return read()
    except HtnError as exc:
        if exc.file == source and exc.line is not None:
            exc.line = max(exc.line - 1, 1)
        raise


class _Var(str):
    """A pattern's ``?variable``."""


def _pattern(text: str) -> tuple[str, tuple[str | float, ...]]:
    """``(at ?who kitchen)`` -> ``("at", (_Var("?who"), "kitchen"))``: one
    flat atom of symbols, numbers and variables (what a query asks)."""
    inner = text.strip()
    if (
        not (inner.startswith("(") and inner.endswith(")"))
        or "(" in inner[1:-1]
        or ")" in inner[1:-1]
        or not inner[1:-1].split()
    ):
        raise HtnError(
            "a pattern is one atom of symbols, numbers and ?variables, e.g. (robot_at ?who ?where)",
            "pattern",
            1,
            1,
        )
    pred, *words = inner[1:-1].lower().split()
    args: list[str | float] = []
    for w in words:
        if w.startswith("?"):
            args.append(_Var(w))
            continue
        try:
            args.append(float(w))
        except ValueError:
            args.append(w)
    return pred, tuple(args)


def _matches(pattern: tuple[object, ...], args: tuple[object, ...]) -> bool:
    if len(pattern) != len(args):
        return False
    bound: dict[_Var, object] = {}
    for p, a in zip(pattern, args):
        if isinstance(p, _Var):
            if bound.setdefault(p, a) != a:
                return False
        elif p != a:
            return False
    return True


def plan_goal(
    world: WorldModel,
    tasks: str,
    *,
    source: str = "goal",
    timeout: float | None = None,
    stops: Guard | None = None,
    **options: Any,
) -> PlanStream:
    """The plans of the goal ``tasks`` from the facts believed now (a
    :class:`htn.api.plan.PlanStream`; ``options`` as :func:`htn.api.plan.plan`)."""
    from .plan import plan

    return plan(
        world.domain,
        world.problem(tasks, source),
        timeout=timeout,
        functions=world.functions,
        stops=stops,
        **options,
    )
