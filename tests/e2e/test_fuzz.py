"""Property-based fuzzing of the input side: every input gets a clean answer.

Hypothesis mutates the JSHOP2 corpus (domains, problems), the IPC 2020 HDDL
sample (each domain with its smallest instance) and the bundled domains and
problems - deleting, duplicating, swapping and inserting tokens,
nesting deeply, breaking the encoding - and runs ``htn plan`` and ``htn
validate`` on the result through the command line's entry point, in this
process (:func:`conftest.run_htn`: a subprocess per input would allow only a
few hundred inputs in the time budget). For every input:

* the exit code is 0, 1 or 2;
* no exception escapes (no traceback);
* an exit code 2 comes with ``file:line:col:`` at the start of its message;
* no signal is left blocked, no handler or timer left behind (a deadline
  that came while a plan was written once left SIGINT, SIGTERM and SIGALRM
  blocked in the process, and in every process it started after).

CI runs a fixed, derandomized sample of ``HTN_FUZZ_EXAMPLES`` inputs (default
500, about 25 s on two cores). Run it longer, with fresh random inputs, like this::

    HTN_FUZZ_EXAMPLES=10000 HTN_FUZZ_RANDOM=1 python -m pytest tests/e2e/test_fuzz.py -s

(``-s`` shows the tally of inputs and exit codes at the end; ``HTN_FUZZ_SHOW=1``
also prints the first line of each error, to see what the mutants provoke.)
"""

from __future__ import annotations

import json
import os
import re
import signal
import sys
from collections import Counter
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import CORPUS, FUNCTIONS, ROOT, SHARED, corpus_available, run_htn
from fuzz_mutations import mutants

sys.setrecursionlimit(max(sys.getrecursionlimit(), 20000))  # as htn's main() does
EXAMPLES = int(os.environ.get("HTN_FUZZ_EXAMPLES", "500"))
RANDOM = bool(os.environ.get("HTN_FUZZ_RANDOM"))
IPC = SHARED / "corpus" / "ipc2020-to"
VERDICTS = SHARED / "corpus" / "ipc-verdicts" / "ipc2020-to"
LOCATED = re.compile(r"^[^\n]+:\d+:\d+: ")

FUNCTION_FILES = {"freecell": FUNCTIONS / "freecell.py", "test": FUNCTIONS / "test.py"}
SLOW = {"blocks-problem", "rover"}  # seconds per plan: their mutants mostly time out


def _cases() -> list[tuple[Path, Path, Path | None, Path | None]]:
    """(domain, problem, functions, a plan file) of each example."""
    cases = []
    if corpus_available():
        for folder in sorted(p for p in CORPUS.iterdir() if p.is_dir()):
            if folder.name in SLOW and not RANDOM:
                continue
            stats = json.loads((folder / "stats.json").read_text())
            plans = folder / "plans-first.txt"
            if "Plan cost:" not in plans.read_text():
                plans = None  # JSHOP2 found none: nothing to validate
            cases.append(
                (
                    folder / stats["domain_file"],
                    folder / stats["problem_file"],
                    FUNCTION_FILES.get(folder.name),
                    plans,
                )
            )
    if IPC.is_dir():
        for folder in sorted(p for p in IPC.iterdir() if p.is_dir()):
            problem = sorted(folder.glob("p*.hddl"))[0]
            plan = VERDICTS / folder.name / f"{problem.stem}.plan"  # IPC format
            cases.append((folder / "domain.hddl", problem, None, plan if plan.is_file() else None))
    for problem in sorted((ROOT / "problems").glob("*.jshop")):
        domain = re.search(r"\(defproblem\s+\S+\s+(\S+)", problem.read_text()).group(1)
        cases.append((ROOT / "domains" / f"{domain}.jshop", problem, None, None))
    return cases


CASES = _cases()

TALLY: Counter = Counter()


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    if TALLY:
        print(
            f"\nfuzz: {sum(v for k, v in TALLY.items() if k.startswith('exit'))} inputs; "
            + ", ".join(f"{k} {v}" for k, v in sorted(TALLY.items()))
        )


@pytest.mark.skipif(not CASES, reason="no example files")
@settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=not RANDOM,
    database=None,
    suppress_health_check=list(HealthCheck),
)
@pytest.mark.slow
@given(data=st.data())
def test_every_mutant_gets_a_clean_answer(tmp_path_factory, data):
    domain, problem, functions, plans = data.draw(st.sampled_from(CASES), label="example")
    which = data.draw(st.sampled_from(["domain", "problem", "both"]), label="mutate")
    folder = tmp_path_factory.mktemp("mutant")
    d, p = folder / domain.name, folder / (problem.name + ".p")
    d.write_bytes(
        data.draw(mutants(domain.read_text()), label="domain")
        if which != "problem"
        else domain.read_bytes()
    )
    p.write_bytes(
        data.draw(mutants(problem.read_text()), label="problem")
        if which != "domain"
        else problem.read_bytes()
    )
    extra = ["--functions", functions] if functions else []
    command = data.draw(
        st.sampled_from(["plan", "plan", "plan", "validate"] if plans else ["plan"]),
        label="command",
    )
    if command == "plan":
        formats = ["jshop", "json", "text"] + (["ipc"] if domain.suffix == ".hddl" else [])
        fmt = data.draw(st.sampled_from(formats), label="format")
        how = data.draw(st.sampled_from([["-n", "1"], ["-n", "3"], ["--all"]]), label="plans")
        argv = ["plan", d, p, "-f", fmt, *how, "--timeout", "0.5", "-o", folder / "out.txt", *extra]
    else:
        argv = ["validate", d, p, plans, *extra]
    # run_htn fails the test (inprocess.LeakedState) if the command leaves
    # a signal blocked, a handler changed or a timer running; it forgets the
    # compiled code of each mutant (a new domain) as a process's end would
    r = run_htn(*argv)
    code, err = r.returncode, r.stderr
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, ())  # and nothing is blocked now
    assert not blocked & {signal.SIGINT, signal.SIGTERM, signal.SIGALRM}, blocked
    TALLY[f"exit {code}"] += 1
    TALLY[command] += 1
    assert code in (0, 1, 2), (code, err)
    assert "Traceback" not in err, err
    if code == 2:
        assert LOCATED.match(err), err
        TALLY["located errors"] += 1
        if os.environ.get("HTN_FUZZ_SHOW"):
            print(err.splitlines()[0][-150:])
