"""The files ``htn plan`` writes as plans are found: the plan file (``-o``)
and the task trees in Graphviz (``--dot``).

The rule of :class:`PlanFiles`: the paths are checked before any work, and
a file is replaced only by a complete result, one that holds at least one
whole plan (also after a timeout, Ctrl-C, SIGTERM or a closed stdout);
otherwise an earlier file stays. A plan counts once it is wholly written:
the figures a command reports (:meth:`PlanFiles.totals`) are those of what
its files and streams hold.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from htn.files import AtomicFile
from htn.jshop.plans.planfile import header, plan_text

if TYPE_CHECKING:
    from htn.jshop.plans.plan import Plan
    from htn.jshop.plans.tree import TaskTree

    from .plan import PlanStream


class PlanFiles:
    """``output`` (a plan file) and ``dot`` (task trees), either may be None;
    ``inputs``: the command's input files, which they may not overwrite."""

    def __init__(self, output: str | None, dot: str | None, inputs: Iterable[str | None] = ()):
        self.output_path, self.dot_path = output, dot
        self.plans = 0
        self.shortest: int | None = None
        self.out: AtomicFile | None = None
        self.dot: _DotFile | None = None
        read = tuple(inputs)
        try:
            if output:
                self.out = AtomicFile(output, "-o", read, [(dot, "--dot")] if dot else ())
            if dot:
                self.dot = _DotFile(
                    AtomicFile(dot, "--dot", read, [(output, "-o")] if output else ())
                )
        except BaseException:
            self.close()
            raise

    def __enter__(self) -> PlanFiles:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def begin(self, stream: PlanStream) -> None:
        """The plan file's header: the files the plans of ``stream`` (a
        :class:`htn.api.plan.PlanStream`) are made from."""
        if self.out:
            self.out.write(
                header(
                    self.out.path,
                    stream.domain_file,
                    stream.problem_file,
                    stream.functions.source,
                    stream.functions.sha256,
                )
            )

    def add(self, plan: Plan) -> None:
        """Write ``plan`` to the files (flushed: it outlives the process)."""
        if self.out:
            self.out.write(plan_text(plan))
            self.out.flush()
        if self.dot and plan.tree is not None:
            self.dot.add(plan.tree)

    def count(self, plan: Plan) -> None:
        """``plan`` is wholly written, to the files and the output stream."""
        self.plans += 1
        if self.shortest is None or len(plan.steps) < self.shortest:
            self.shortest = len(plan.steps)

    def totals(self, stats: dict[str, Any]) -> dict[str, Any]:
        """``stats`` (a stream's) with the plans found as written."""
        return {**stats, "plans_found": self.plans, "shortest_plan": self.shortest}

    def close(self) -> None:
        """Replace the files if a plan was written, else leave them as they were."""
        for sink in (self.out, self.dot):
            if sink is None:
                continue
            if self.plans:
                sink.commit()
            else:
                sink.discard()
        self.out = self.dot = None

    @property
    def paths(self) -> list[str]:
        return [p for p in (self.output_path, self.dot_path) if p]


class _DotFile:
    """Task trees streamed to a Graphviz file: one ``digraph task_tree`` for
    a single plan, ``digraph plan_N`` for each of several (only the first
    tree is held back, until it is known whether a second one comes)."""

    def __init__(self, file: AtomicFile):
        self.file = file
        self.count = 0
        self.first: str | None = None

    def add(self, tree: TaskTree) -> None:
        self.count += 1
        if self.count == 1:
            self.first = tree.to_dot()
            return
        if self.count == 2:
            assert self.first is not None  # held back by the first add
            self._write(1, self.first)
            self.first = None
        self._write(self.count, tree.to_dot())

    def _write(self, i: int, text: str) -> None:
        self.file.write(text.replace("digraph task_tree", f"digraph plan_{i}", 1))

    def commit(self) -> None:
        if self.first is not None:
            self.file.write(self.first)
        self.file.commit()

    def discard(self) -> None:
        self.file.discard()
