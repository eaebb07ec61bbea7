"""``htn plan DOMAIN PROBLEM``: its options (the body is :mod:`.plan_run`)."""

from __future__ import annotations

import click

from htn.api.plan import DEFAULT_MAX_DEPTH, SEARCHES

from .fast import FORMATS
from .options import TIMEOUT_HELP, Count, Timeout, current_stops, memory_mb
from .plan_run import run_plan


@click.command("plan")
@click.argument("domain", type=click.Path(dir_okay=False))
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option(
    "-n",
    "--plans",
    "n_plans",
    type=Count(),
    default=1,
    show_default=True,
    help="Stop after the first N plans (per problem in the file).",
)
@click.option(
    "-a",
    "--all",
    "all_plans",
    is_flag=True,
    help="Enumerate every plan (JSHOP2's -ra); stream them as they are found.",
)
@click.option(
    "-f",
    "--format",
    "fmt",
    type=click.Choice(list(FORMATS)),
    help="Output format [default: text on a terminal, else jshop]. 'jshop' prints "
    "exactly what JSHOP2 prints; 'json' is JSON Lines: one object per plan "
    "(steps, cost, task tree), then one with the statistics; 'ipc' the IPC "
    "2020 HTN plan format (actions and decompositions), which the "
    "competition's verifier reads.",
)
@click.option(
    "-o",
    "--output",
    type=click.Path(dir_okay=False),
    help="Also write the plans (jshop format, with a header naming the domain and "
    "problem files, and each plan's task tree as comment lines) to this file, "
    "for 'htn run'.",
)
@click.option(
    "--timeout",
    type=Timeout(),
    metavar="SECONDS",
    help=TIMEOUT_HELP + " The search stops then and keeps what was found.",
)
@click.option(
    "--functions",
    type=click.Path(dir_okay=False),
    metavar="FILE.py",
    help="Python file whose public functions can be called with (call name ...) "
    "and used as :sort-by comparators.",
)
@click.option(
    "--tree",
    "show_tree",
    is_flag=True,
    help="Show each plan's task tree (decompositions, branches, paths).",
)
@click.option(
    "--dot",
    type=click.Path(dir_okay=False),
    metavar="FILE",
    help="Write the task tree(s) as Graphviz DOT.",
)
@click.option(
    "-q",
    "--quiet",
    is_flag=True,
    help="Do not print domain warnings, nor why there is no plan (unless --explain).",
)
@click.option(
    "--jshop2-compat",
    is_flag=True,
    help="Reproduce JSHOP2 1.0.3 exactly: a method body written (:unordered ...) "
    "runs in order [default: unordered, as the JSHOP2 manual says].",
)
@click.option(
    "--max-depth",
    type=Count(),
    default=DEFAULT_MAX_DEPTH,
    show_default=True,
    metavar="N",
    help="Stop a search that nests more than N method reductions without an "
    "operator in between (a method that decomposes into itself without end).",
)
@click.option(
    "--max-memory",
    type=Count(1, memory_mb()),
    metavar="MB",
    help="Stop a search whose process reaches this much resident memory "
    "[default: 80% of the memory available, and of ulimit -v if set].",
)
@click.option(
    "--explain",
    is_flag=True,
    help="Say why there is no plan (also printed when there is none): the deepest "
    "dead end of the search, each operator or method tried and the precondition "
    "literal that failed, with file:line:col.",
)
@click.option("--explain-all", is_flag=True, help="Like --explain, listing every dead end.")
@click.option(
    "--search",
    "search_name",
    type=click.Choice(list(SEARCHES)),
    default="dfs",
    show_default=True,
    help="How to search: "
    + "; ".join(f"{k}: {v}" for k, v in SEARCHES.items())
    + ". See docs/hddl.md.",
)
def plan(domain, problem, fmt, output, timeout, functions, show_tree, dot, quiet, **flags):
    """Find plans for PROBLEM in DOMAIN (JSHOP2 or HDDL files).

    \b
    Examples:
      htn plan domains/domestic.jshop problems/bring_object.jshop
      htn plan domain.hddl p01.hddl -f ipc --search auto
      htn plan DOMAIN PROBLEM --all --format jshop
      htn plan DOMAIN PROBLEM -o plan.txt && htn run plan.txt --sim
    """
    run_plan(
        current_stops(),
        domain,
        problem,
        fmt,
        output,
        timeout,
        functions,
        show_tree,
        dot,
        quiet,
        **flags,
    )
