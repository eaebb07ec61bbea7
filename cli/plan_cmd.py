"""``htn plan DOMAIN PROBLEM``: find plans and print them."""
from __future__ import annotations

import contextlib
import json
import sys
import time

import click

from htn.jshop.limits import DEFAULT_MAX_DEPTH

from .output import atomic_write, deferred_interrupt, stdout_is_terminal, warn

FORMATS = ["text", "jshop", "json", "ipc"]


@click.command("plan")
@click.argument("domain", type=click.Path(dir_okay=False))
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option("-n", "--plans", "n_plans", type=click.IntRange(min=1), default=1, show_default=True,
              help="Stop after the first N plans (per problem in the file).")
@click.option("-a", "--all", "all_plans", is_flag=True,
              help="Enumerate every plan (JSHOP2's -ra); stream them as they are found.")
@click.option("-f", "--format", "fmt", type=click.Choice(FORMATS),
              help="Output format [default: text on a terminal, else jshop]. 'jshop' prints "
                   "exactly what JSHOP2 prints; 'json' one object with plans, trees and stats; "
                   "'ipc' the IPC 2020 HTN plan format (actions and decompositions), which "
                   "the competition's verifier reads.")
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Also write the plans (jshop format, with a header naming the domain and "
                   "problem files) to this file, for 'htn run'.")
@click.option("--timeout", type=click.FloatRange(min=0, min_open=True), metavar="SECONDS",
              help="Stop searching after this many seconds and keep what was found.")
@click.option("--functions", type=click.Path(dir_okay=False), metavar="FILE.py",
              help="Python file whose public functions can be called with (call name ...) "
                   "and used as :sort-by comparators.")
@click.option("--tree", "show_tree", is_flag=True,
              help="Show each plan's task tree (decompositions, branches, paths).")
@click.option("--dot", type=click.Path(dir_okay=False), metavar="FILE",
              help="Write the task tree(s) as Graphviz DOT.")
@click.option("-q", "--quiet", is_flag=True,
              help="Do not print domain warnings, nor why there is no plan (unless --explain).")
@click.option("--jshop2-compat", is_flag=True,
              help="Reproduce JSHOP2 1.0.3 exactly: a method body written (:unordered ...) "
                   "runs in order [default: unordered, as the JSHOP2 manual says].")
@click.option("--max-depth", type=click.IntRange(min=1), default=DEFAULT_MAX_DEPTH,
              show_default=True, metavar="N",
              help="Stop a search that nests deeper than N reductions and steps "
                   "(a method that decomposes into itself without end).")
@click.option("--explain", is_flag=True,
              help="Say why there is no plan (also printed when there is none): the deepest "
                   "dead end of the search, each operator or method tried and the precondition "
                   "literal that failed, with file:line:col.")
@click.option("--explain-all", is_flag=True, help="Like --explain, listing every dead end.")
def plan(domain, problem, n_plans, all_plans, fmt, output, timeout, functions,
         show_tree, dot, quiet, jshop2_compat, max_depth, explain, explain_all):
    """Find plans for PROBLEM in DOMAIN (JSHOP2 files).

    \b
    Examples:
      htn plan domains/domestic.jshop problems/bring_object.jshop
      htn plan DOMAIN PROBLEM --all --format jshop
      htn plan DOMAIN PROBLEM -o plan.txt && htn run plan.txt --sim
    """
    from htn.jshop.checks import check_domain, check_problem
    from htn.jshop.functions import FunctionTable
    from htn.jshop.parser import load_domain, load_problem
    from htn.jshop.planfile import header
    from htn.jshop.planner import Planner, compat_warning

    fmt = fmt or ("text" if stdout_is_terminal() else "jshop")
    table = FunctionTable()
    if functions:
        table.load_file(functions)
    dom = load_domain(domain, table)
    prob = load_problem(problem, table)
    warnings = check_domain(dom) + check_problem(dom, prob)
    if jshop2_compat and compat_warning(dom):
        warnings.append(compat_warning(dom))
    if not quiet:
        for w in warnings:
            warn(w)
    limit = None if all_plans else n_plans
    record_trees = show_tree or bool(dot) or fmt in ("json", "ipc")
    render = _Renderer(fmt, show_tree)
    render.spelling = {**prob.spelling, **dom.spelling}
    found = []      # whole plans, kept only when --format json or --dot needs them
    explainers = []  # one per problem instance, see --explain
    lengths = []    # of every plan streamed (memory stays flat for --all)
    totals = {"plans_found": 0, "search_ms": 0.0, "expansions": 0,
              "operator_applications": 0, "backtracks": 0, "timed_out": False,
              "interrupted": False, "depth_limit_reached": False}
    started = time.perf_counter()
    interrupted = False
    # -o: Ctrl-C keeps the whole plans written so far; any other error leaves
    # an earlier file untouched (atomic_write discards the temporary file)
    with contextlib.ExitStack() as files:
        out_fh = files.enter_context(atomic_write(output)) if output else None
        if out_fh:
            out_fh.write(header(output, domain, problem, functions))
        try:
            for k, inst in enumerate(prob.instances):
                remaining = None
                if timeout is not None:
                    remaining = timeout - (time.perf_counter() - started)
                    if remaining <= 0:
                        totals["timed_out"] = True
                        break
                explainer = None
                if explain or explain_all:
                    from htn.jshop.explain import Explainer
                    explainer = Explainer(keep_all=explain_all)
                    explainers.append(explainer)
                planner = Planner(dom, inst, table, record_trees=record_trees,
                                  jshop2_compat=jshop2_compat, max_depth=max_depth,
                                  explain=explainer)
                try:
                    for p in planner.plans(remaining):
                        p.instance = k
                        with deferred_interrupt():
                            render.plan(p)
                            if out_fh:
                                out_fh.write(p.to_jshop())
                                out_fh.flush()
                            lengths.append(len(p.steps))
                        if fmt == "json" or dot:
                            found.append(p)
                        if limit is not None and planner.stats.plans_found >= limit:
                            break
                finally:
                    _add_stats(totals, planner.stats.as_dict())
                if planner.stats.timed_out:
                    totals["timed_out"] = True
                    break
                if planner.stats.depth_limit is not None:
                    totals["depth_limit_reached"] = True
                    warn(planner.stats.depth_limit)
                    break
        except KeyboardInterrupt:
            interrupted = True
            totals["interrupted"] = True
    totals["shortest_plan"] = min(lengths) if lengths else None
    totals["search_ms"] = round(totals["search_ms"], 3)
    if dot:
        _write_dot(dot, found)
    if not lengths and not explainers and not quiet and not interrupted \
            and not totals["timed_out"] and not totals["depth_limit_reached"]:
        # no plan: search again, recording dead ends this time (planning
        # without --explain pays nothing for them)
        from htn.jshop.explain import explain_search
        explainers = [explain_search(dom, inst, table, jshop2_compat=jshop2_compat,
                                     max_depth=max_depth) for inst in prob.instances]
    if explainers:
        totals["explain"] = [e.to_dict(full=explain_all) for e in explainers]
        if fmt != "json":
            for e in explainers:
                for line in e.lines(full=explain_all):
                    warn(line)
    render.finish(found, totals, domain, problem, any_plan=bool(lengths))
    if totals["timed_out"]:
        warn(f"timed out after {timeout:g} s; {totals['plans_found']} plan(s) found")
    if interrupted:
        warn(f"interrupted; {totals['plans_found']} plan(s) found")
        sys.exit(130)
    if not lengths:
        if fmt == "text":
            warn("no plan found")
        sys.exit(1)


def _add_stats(totals: dict, s: dict) -> None:
    for key in ("plans_found", "expansions", "operator_applications", "backtracks"):
        totals[key] += s[key]
    totals["search_ms"] += s["search_ms"]


def _write_dot(path: str, plans) -> None:
    with atomic_write(path) as fh:
        trees = [p for p in plans if getattr(p, "tree", None) is not None]
        if len(trees) == 1:
            fh.write(trees[0].tree.to_dot())
        else:
            for i, p in enumerate(trees, 1):
                fh.write(p.tree.to_dot().replace("digraph task_tree", f"digraph plan_{i}", 1))


class _Renderer:
    """Prints plans as they stream in, in one of the three formats."""

    def __init__(self, fmt: str, show_tree: bool):
        self.fmt = fmt
        self.show_tree = show_tree
        self.count = 0
        self._console = None
        self.spelling: dict = {}

    @property
    def console(self):
        if self._console is None:
            from rich.console import Console
            self._console = Console(highlight=False)
        return self._console

    def plan(self, p) -> None:
        self.count += 1
        if self.fmt == "jshop":
            sys.stdout.write(p.to_jshop())
            sys.stdout.flush()
            if self.show_tree and p.tree is not None:
                from .tree_view import rich_tree
                from rich.console import Console
                Console(stderr=True, highlight=False).print(rich_tree(p.tree))
        elif self.fmt == "text":
            self._text_plan(p)
        elif self.fmt == "ipc":
            from htn.jshop.ipc import ipc_text
            sys.stdout.write(ipc_text(p, self.spelling))
            sys.stdout.flush()

    def _text_plan(self, p) -> None:
        from rich.table import Table
        from rich import box
        from htn.jshop.terms import java_double
        c = self.console
        c.print(f"[bold]Plan {self.count}[/bold]  cost {java_double(p.cost)}  "
                f"{len(p.steps)} step{'s' if len(p.steps) != 1 else ''}")
        t = Table(box=box.SIMPLE, show_header=False, padding=(0, 1))
        t.add_column(justify="right", style="dim")
        t.add_column()
        for i, s in enumerate(p.steps, 1):
            t.add_row(str(i), f"[dim]{s}[/dim]" if s.internal else str(s))
        c.print(t)
        if self.show_tree and p.tree is not None:
            from .tree_view import rich_tree
            c.print(rich_tree(p.tree))

    def finish(self, plans, totals: dict, domain: str, problem: str, any_plan: bool) -> None:
        if self.fmt == "json":
            doc = {
                "domain": domain,
                "problem": problem,
                "plans": [{"instance": getattr(p, "instance", 0),
                           "steps": p.lines(), "cost": p.cost, "length": len(p.steps),
                           "tree": p.tree.to_dict() if p.tree is not None else None}
                          for p in plans],
                "stats": totals,
            }
            sys.stdout.write(json.dumps(doc, indent=1) + "\n")
        elif self.fmt == "text":
            shortest = totals["shortest_plan"]
            extra = f", shortest plan {shortest} steps" if shortest is not None else ""
            self.console.print(
                f"[bold]{totals['plans_found']}[/bold] plan(s) found; search "
                f"{totals['search_ms']:.1f} ms{extra}; {totals['expansions']} expansions, "
                f"{totals['backtracks']} backtracks", style="green" if any_plan else "red")
