"""A plain ``htn plan DOMAIN PROBLEM`` recognised without click.

Importing click costs a small problem's planning time twice over (about 30
ms of CPU here), so a command line that needs none of click's work runs the
plan command directly (:func:`htn.cli.plan_run.run_plan`): two file names
and, at most, the options ``-f``/``--format`` with one of the formats,
``-q``/``--quiet`` and ``--search dfs`` or ``auto``, each given once. Anything else (any
other option, ``--help``, a value click would refuse or convert, a name
that starts with ``-`` or is a folder) is left to click, which gives the
same defaults and its own messages: the options here mean exactly what they
mean there, and ``tests/cli/test_fast.py`` compares both ways.
"""

from __future__ import annotations

import os
from typing import Any

# htn plan -f: the one list (plan_cmd and plan_run take it from here)
FORMATS = ("text", "jshop", "json", "ipc")
_VALUED = {"-f": "fmt", "--format": "fmt", "--search": "search_name"}
_FLAGS = {"-q": "quiet", "--quiet": "quiet"}


def plain_plan(args: list[str]) -> dict[str, Any] | None:
    """``run_plan``'s arguments for a plain ``htn plan`` command line, or None."""
    if len(args) < 3 or args[0] != "plan":
        return None
    given: dict[str, Any] = {}
    files: list[str] = []
    rest = iter(args[1:])
    for arg in rest:
        if arg in _FLAGS and _FLAGS[arg] not in given:
            given[_FLAGS[arg]] = True
        elif arg in _VALUED and _VALUED[arg] not in given:
            given[_VALUED[arg]] = next(rest, None)
        elif arg.startswith("-") or arg == "" or os.path.isdir(arg):
            return None  # an option, "--", or what click checks or refuses
        else:
            files.append(arg)
    if len(files) != 2 or given.get("fmt", "text") not in FORMATS:
        return None
    search = given.get("search_name", "dfs")
    if search not in ("dfs", "auto"):
        # gbfs and wastar may refuse JSHOP2 input, a usage error click shows;
        # dfs and auto refuse only with --all or --jshop2-compat
        # (htn.jshop.search.searches.refusal), which the fast path leaves to click
        return None
    from htn.api.plan import DEFAULT_MAX_DEPTH  # the use case, which runs next anyway

    return {
        "domain": files[0],
        "problem": files[1],
        "fmt": given.get("fmt"),
        "output": None,
        "timeout": None,
        "functions": None,
        "show_tree": False,
        "dot": None,
        "quiet": given.get("quiet", False),
        # the defaults of plan_cmd's options
        "n_plans": 1,
        "all_plans": False,
        "jshop2_compat": False,
        "max_depth": DEFAULT_MAX_DEPTH,
        "max_memory": None,
        "explain": False,
        "explain_all": False,
        "search_name": search,
    }
