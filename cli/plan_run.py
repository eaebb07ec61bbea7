"""The body of ``htn plan``, without click: :mod:`.plan_cmd` calls it with
the options click parsed, :mod:`.fast` with those of a plain command line.

Every format streams: a plan is printed (and written to ``-o``/``--dot``) when
the planner finds it and then forgotten, so ``--all`` runs in flat memory
until it ends, times out or is interrupted. ``-f json`` is JSON Lines: one
object per plan, then one with the statistics (see docs/commands/plan.md).
"""

from __future__ import annotations

import sys

from htn.api.plan import UnsupportedSearch
from htn.api.plan import plan as find_plans
from htn.api.plan_files import PlanFiles
from htn.process import DeadlineExceeded, Stops, deadline

from .output import console, stdout_is_terminal, warn
from .progress import Phase

EXPLAIN_GRACE = 0.25  # s after --timeout for the explaining search to stop itself


def run_plan(
    stops: Stops, domain, problem, fmt, output, timeout, functions, show_tree, dot, quiet, **flags
) -> None:
    """Find plans for PROBLEM in DOMAIN and print them (``flags``: n_plans,
    all_plans, jshop2_compat, max_depth, max_memory, explain, explain_all,
    search_name)."""
    fmt = fmt or ("text" if stdout_is_terminal() else "jshop")
    trees = show_tree or bool(dot) or bool(output) or fmt in ("json", "ipc")
    explain_all = flags["explain_all"]
    options = dict(
        plans=None if flags["all_plans"] else flags["n_plans"],
        timeout=timeout,
        functions=functions,
        jshop2_compat=flags["jshop2_compat"],
        max_depth=flags["max_depth"],
        max_memory=flags["max_memory"],
        explain=flags["explain"] or explain_all,
        explain_all=explain_all,
        search=flags["search_name"],
        trees=trees,
        tree_paths=show_tree or bool(dot) or fmt == "json",
        stops=stops,
    )
    # -o and --dot are checked before any work, and replaced only by a
    # complete new result (htn.api.plan_files)
    with PlanFiles(output, dot, (domain, problem, functions)) as files:
        plans = _open(domain, problem, options, stops)
        if not quiet:
            for w in plans.warnings:
                warn(w)
        files.begin(plans)
        render = _Renderer(fmt, show_tree, domain, problem)
        # objects as the problem spells them (HDDL names are case-insensitive)
        render.spelling = {**plans.domain.spelling, **plans.problem.spelling}
        stop = _stream(plans, files, render, stops, timeout)
    _finish(plans, files, render, stop, stops, quiet, explain_all, timeout)


def _open(domain, problem, options: dict, stops):
    """The stream of plans (reading a large HDDL instance can take seconds:
    a spinner says so, on a terminal, after a second; it counts toward
    --timeout too)."""
    try:
        with (
            deadline(stops, options["timeout"], stops.started),
            Phase("reading the domain and the problem"),
        ):
            return find_plans(domain, problem, **options)
    except UnsupportedSearch as exc:
        import click  # a usage error, shown as click shows its own

        raise click.UsageError(exc.message) from None


def _stream(plans, files, render, stops, timeout):
    """Write and print each plan as it is found; the stop that ended the
    search early (Ctrl-C, SIGTERM, a closed stdout), if any."""
    try:
        with deadline(stops, timeout, stops.started), plans, Phase("planning") as phase:
            for p in plans:
                phase.end()
                with stops.held():  # the files first: they outlive a closed stdout
                    files.add(p)
                    files.count(p)
                    render.plan(p)
                stops.raise_again()  # a Ctrl-C a finalizer swallowed
    except DeadlineExceeded:
        plans.stats["timed_out"] = True
    except (KeyboardInterrupt, BrokenPipeError) as exc:
        plans.stats["interrupted"] = isinstance(exc, KeyboardInterrupt)
        return exc
    return None


def _finish(plans, files, render, stop, stops, quiet, explain_all, timeout) -> None:
    """The statistics, the explanations, the warnings and the exit code."""
    totals = files.totals(plans.stats)  # what the streams and files hold
    found = files.plans
    if plans.bound is not None:
        warn(plans.bound)
    if isinstance(stop, BrokenPipeError):
        raise stop  # the reader went away: main() exits quietly
    if (
        not found
        and not quiet
        and stop is None
        and not totals["timed_out"]
        and not totals["depth_limit_reached"]
        and not totals["memory_limit_reached"]
    ):
        # bounded by --timeout: the API stops the search that explains in time and
        # keeps the dead ends it met; the deadline, a moment later, stops the rest
        late = None if timeout is None else timeout + EXPLAIN_GRACE
        try:
            with deadline(stops, late, stops.started):
                plans.explain()
        except DeadlineExceeded:
            warn(f"explain: --timeout {timeout:g} s ended the search that explains")
    if plans.explanations:
        totals["explain"] = [e.to_dict(full=explain_all) for e in plans.explanations]
        if render.fmt != "json":
            for e in plans.explanations:
                for line in e.lines(full=explain_all):
                    warn(line)
    render.finish(totals)
    if totals["timed_out"]:
        warn(f"timed out after {timeout:g} s; {found} plan(s) found")
    if isinstance(stop, KeyboardInterrupt):
        stops.interrupt_exit(stop, f"{found} plan(s) found")
    if not found:
        _nothing_found(render.fmt, totals, quiet, stop, files.paths)


def _nothing_found(fmt, totals, quiet, stop, paths) -> None:
    if fmt == "text":
        warn("no plan found")
    if totals.get("loop_cuts") and not quiet and not totals["timed_out"] and stop is None:
        warn(
            f"the loop check cut {totals['loop_cuts']} reduction(s) that revisit a state: "
            "a plan that needs them may exist (--search auto searches without it)"
        )
    for path in paths:
        warn(f"{path}: not written (no plan)")
    sys.exit(1)


class _Renderer:
    """Prints plans as they stream in, in one of the four formats."""

    def __init__(self, fmt: str, show_tree: bool, domain: str, problem: str):
        self.fmt = fmt
        self.show_tree = show_tree
        self.domain = domain
        self.problem = problem
        self.count = 0
        self._console = None
        self.spelling: dict = {}  # lower-case name -> as the input wrote it (HDDL)

    @property
    def console(self):
        if self._console is None:
            self._console = console(highlight=False)
        return self._console

    def plan(self, p) -> None:
        self.count += 1
        if self.fmt == "jshop":
            sys.stdout.write(p.to_jshop())
            sys.stdout.flush()
            if self.show_tree and p.tree is not None:
                # asked for, so on stdout (piped too), after the plan it explains
                from .tree_view import rich_tree

                self.console.print(rich_tree(p.tree))
        elif self.fmt == "text":
            self._text_plan(p)
        elif self.fmt == "ipc":
            from htn.api.plan import ipc_text

            sys.stdout.write(ipc_text(p, self.spelling))
            sys.stdout.flush()
        else:
            self._json_line(
                {
                    "type": "plan",
                    "instance": getattr(p, "instance", 0),
                    "index": p.index,
                    "cost": p.cost,
                    "length": len(p.steps),
                    "steps": p.lines(),
                    "tree": p.tree.to_dict() if p.tree is not None else None,
                }
            )

    def _json_line(self, record: dict) -> None:
        import json  # -f json only

        sys.stdout.write(json.dumps(record, separators=(",", ":")) + "\n")
        sys.stdout.flush()

    def _text_plan(self, p) -> None:
        from rich import box
        from rich.table import Table

        from htn.api.plan import java_double

        c = self.console
        c.print(
            f"[bold]Plan {self.count}[/bold]  cost {java_double(p.cost)}  "
            f"{len(p.steps)} step{'s' if len(p.steps) != 1 else ''}"
        )
        t = Table(box=box.SIMPLE, show_header=False, padding=(0, 1))
        t.add_column(justify="right", style="dim")
        t.add_column()
        for i, s in enumerate(p.steps, 1):
            t.add_row(str(i), f"[dim]{s}[/dim]" if s.internal else str(s))
        c.print(t)
        if self.show_tree and p.tree is not None:
            from .tree_view import rich_tree

            c.print(rich_tree(p.tree))

    def finish(self, totals: dict) -> None:
        if self.fmt == "json":
            self._json_line(
                {"type": "stats", "domain": self.domain, "problem": self.problem, **totals}
            )
        elif self.fmt == "text":
            shortest = totals["shortest_plan"]
            extra = f", shortest plan {shortest} steps" if shortest is not None else ""
            if "found_by" in totals:
                extra += f", found by {totals['found_by']}"
            self.console.print(
                f"[bold]{totals['plans_found']}[/bold] plan(s) found; search "
                f"{totals['search_ms']:.1f} ms{extra}; {totals['expansions']} expansions, "
                f"{totals['backtracks']} backtracks",
                style="green" if self.count else "red",
            )
