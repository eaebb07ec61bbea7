"""Golden tests: ``htn plan --format jshop`` is byte-identical to JSHOP2's output.

Ground truth is the original Java JSHOP2's output on its own examples
(``shared/corpus/jshop2``): the first plan (``-r``), all plans where JSHOP2
finished (``-ra``), the first 10 where it did not (``-r10``), and ``-r12`` on
``test``.

Each comparison runs twice: in the default mode (the manual's ``:unordered``
method bodies; the corpus uses ``:unordered`` only in problems, so nothing may
change) and with ``--jshop2-compat`` (JSHOP2 1.0.3 exactly).
"""

from __future__ import annotations

import json

import pytest

from conftest import CORPUS, FUNCTIONS, corpus_available, needs_corpus, run_htn

# user functions the examples call (JSHOP2 ships them as Java classes)
FUNCTION_FILES = {"freecell": FUNCTIONS / "freecell.py", "test": FUNCTIONS / "test.py"}


def _cases():
    if not corpus_available():
        return [pytest.param("corpus", "missing", marks=needs_corpus)]
    cases = []
    for ex in sorted(p.name for p in CORPUS.iterdir() if p.is_dir()):
        stats = json.loads((CORPUS / ex / "stats.json").read_text())
        cases.append((ex, "first"))
        if stats["timed_out_all"]:
            cases.append((ex, "first10"))
        else:
            cases.append((ex, "all"))
        if (CORPUS / ex / "plans-r12.txt").exists():
            cases.append((ex, "r12"))
    return cases


MODES = {
    "first": ("plans-first.txt", ["--plans", "1"]),
    "all": ("plans-all.txt", ["--all"]),
    "first10": ("plans-first10.txt", ["--plans", "10"]),
    "r12": ("plans-r12.txt", ["--plans", "12"]),
}


@needs_corpus
@pytest.mark.parametrize("semantics", ["manual", "jshop2-compat"])
@pytest.mark.parametrize("example,mode", _cases())
def test_matches_jshop2(example, mode, semantics):
    folder = CORPUS / example
    stats = json.loads((folder / "stats.json").read_text())
    golden, flags = MODES[mode]
    args = [
        "plan",
        folder / stats["domain_file"],
        folder / stats["problem_file"],
        "--format",
        "jshop",
        "--quiet",
        *flags,
    ]
    if example in FUNCTION_FILES:
        args += ["--functions", FUNCTION_FILES[example]]
    if semantics == "jshop2-compat":
        args.append("--jshop2-compat")
    result = run_htn(*args)
    assert "Traceback" not in result.stderr
    expected = (folder / golden).read_text()
    assert result.returncode == (0 if expected else 1), result.stderr
    assert result.stdout == expected


@needs_corpus
def test_first_plan_figures_match_stats():
    """The first plan's length and cost agree with each stats.json."""
    from htn.jshop import FunctionTable, Planner, load_domain, load_problem

    for folder in sorted(p for p in CORPUS.iterdir() if p.is_dir()):
        stats = json.loads((folder / "stats.json").read_text())
        table = FunctionTable()
        if folder.name in FUNCTION_FILES:
            table.load_file(str(FUNCTION_FILES[folder.name]))
        dom = load_domain(str(folder / stats["domain_file"]), table)
        prob = load_problem(str(folder / stats["problem_file"]), table)
        plan = next(Planner(dom, prob.instances[0], table).plans(), None)
        if stats["first_plan_length"] is None:
            assert plan is None, folder.name
        else:
            assert len(plan.steps) == stats["first_plan_length"], folder.name
            assert plan.cost == stats["first_plan_cost"], folder.name
