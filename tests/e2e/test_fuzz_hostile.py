"""Fuzzing the rest of the input side (issue 18): options, hostile functions
files and edited logs.

Each input is one command on a small domain whose method calls a user
function:

* **options**: ``--timeout`` drawn from numbers, ``inf``, ``nan``, zero,
  negatives and words; ``-o`` and ``--dot`` drawn from a fresh file, an
  input of the command (the domain, through a symbolic link too), the other
  output, a FIFO, ``/dev/null``, a folder, ``-`` and a missing folder;
* **hostile functions files**: raise each built-in ``BaseException``
  subclass at import or in the function, loop at import, return junk
  (objects whose methods raise, huge numbers, NaN, nested lists), or (in
  a process of its own, :data:`PROCESS_KINDS`) swallow every signal and the
  deadline, or close file descriptor 1;
* **edited logs**: the header of a real run's log with one field replaced
  by a value of another type or range, or the log cut, for ``htn run
  --from-log``.

For every input: exit code 0, 1, 2 (or 130/143 never: nothing interrupts
here), no traceback, an input that is also an output is unchanged, and a
process ends within ``--timeout`` + 5 s of CPU time (and a minute of wall-clock
time: the offline run is nice'd on a shared machine). CI runs ``HTN_FUZZ_EXAMPLES``
(default 200) derandomized inputs in this process; the offline run is
``benchmarks/fuzz_offline.sh`` (fresh seeds, in chunks).
"""

from __future__ import annotations

import builtins
import json
import os
import re
import resource
import time
from collections import Counter

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from conftest import run_htn, run_htn_process

EXAMPLES = int(os.environ.get("HTN_FUZZ_EXAMPLES", "200"))
RANDOM = bool(os.environ.get("HTN_FUZZ_RANDOM"))
# offline (fresh seeds, many inputs): a failure is reported as found, not shrunk
PHASES = [Phase.generate] if RANDOM else list(Phase)
LOCATED = re.compile(r"^[^\n]+:\d+(:\d+)?: ")
USAGE = re.compile(r"^(Usage: |Error: )", re.M)

DOMAIN = """(defdomain d (
  (:operator (!go ?x) () () ((at ?x)))
  (:method (travel ?x) ((assign ?v (call f ?x)) (call ok ?v)) ((!go ?x)))))"""
PROBLEM = "(defproblem p d () ((travel home) (travel work)))"
GOOD = "def f(x):\n    return 1\ndef ok(v):\n    return 1\n"

EXCEPTIONS = sorted(
    n
    for n, v in vars(builtins).items()
    if isinstance(v, type)
    and issubclass(v, BaseException)
    and n not in ("BaseExceptionGroup", "ExceptionGroup")
)
JUNK = [
    "object()",
    "float('nan')",
    "10 ** 400",
    "[[[[]]]] * 3",
    "type('S', (str,), {'lower': lambda s: 1 / 0, '__repr__': lambda s: 1 / 0})('x')",
    "type('F', (float,), {'__float__': lambda s: 1 / 0})(2.0)",
    "{'a': 1}",
    "b'x'",
    "(lambda: 0)",
    "'x' * 100000",
    "list(range(100000))",
    "True",
    "None",
    "-0.0",
]
SWALLOW = (
    "import time\ndef f(x):\n    while True:\n        try:\n            time.sleep(0.05)\n"
    "        except BaseException:\n            pass\ndef ok(v):\n    return 1\n"
)
CLOSE_1 = "import os\nos.close(1)\n" + GOOD
PROCESS_KINDS = {
    "swallow": SWALLOW,
    "close fd 1": CLOSE_1,
    "loop at import, swallowing": "while True:\n    try:\n        pass\n"
    "    except BaseException:\n        pass\n",
}


@st.composite
def functions_files(draw) -> tuple[str, str]:
    """(kind, source) of a hostile (or ordinary) functions file."""
    kind = draw(
        st.sampled_from(
            ["good", "raise at import", "raise in f", "raise in ok", "loop at import", "junk"]
        )
    )
    if kind == "good":
        return kind, GOOD
    if kind == "loop at import":
        return kind, "while True:\n    pass\n" + GOOD
    if kind == "junk":
        return (
            kind,
            f"def f(x):\n    return {draw(st.sampled_from(JUNK))}\ndef ok(v):\n    return 1\n",
        )
    exc = draw(st.sampled_from(EXCEPTIONS))
    raising = f"raise {exc}" if exc != "SystemExit" else "raise SystemExit(3)"
    if kind == "raise at import":
        return f"{kind} {exc}", f"{GOOD}\n{raising}\n"
    name = "f" if kind == "raise in f" else "ok"
    body = GOOD.replace(f"def {name}(", f"def {name}_old(") + f"def {name}(x):\n    {raising}\n"
    return f"{kind} {exc}", body


TIMEOUTS = [
    "0.5",
    "2",
    "inf",
    "1e300",
    "Infinity",
    "nan",
    "0",
    "-1",
    "-inf",
    "1e-9",
    "soon",
    "",
    "0x10",
    "1_0",
]
PATHS = [
    "fresh",
    "domain",
    "link to domain",
    "problem",
    "functions",
    "other output",
    "fifo",
    "/dev/null",
    "folder",
    "-",
    "missing folder",
]


def _path(kind: str, folder, d, p, fns, other):
    return {
        "fresh": folder / "out.txt",
        "domain": d,
        "problem": p,
        "functions": fns,
        "link to domain": folder / "alias",
        "other output": other,
        "fifo": folder / "fifo",
        "/dev/null": "/dev/null",
        "folder": folder,
        "-": "-",
        "missing folder": folder / "no" / "x.txt",
    }[kind]


TALLY: Counter = Counter()


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    if TALLY:
        print(
            f"\nfuzz-hostile: {sum(v for k, v in TALLY.items() if k.startswith('exit'))} "
            "inputs; " + ", ".join(f"{k} {v}" for k, v in sorted(TALLY.items()))
        )


def _setup(folder, source: str):
    d, p, fns = folder / "d.jshop", folder / "p.jshop", folder / "fns.py"
    d.write_text(DOMAIN)
    p.write_text(PROBLEM)
    fns.write_text(source)
    os.mkfifo(folder / "fifo")
    (folder / "alias").symlink_to(d)
    return d, p, fns


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _check(
    r, argv, inputs: dict, limit: float | None, began: float, kind: str, cpu_before: float = 0.0
) -> None:
    code, err = r.returncode, r.stderr
    TALLY[f"exit {code}"] += 1
    assert code in (0, 1, 2), (argv, code, err)
    assert "Traceback" not in err and "Exception ignored" not in err, (argv, err)
    if code == 2:
        # at a line, at a whole file (an output path, a file that cannot be
        # read), or a usage error of an option
        assert (
            LOCATED.match(err)
            or USAGE.search(err)
            or any(err.startswith(f"{a}: ") for a in [*argv[1:], "standard output"])
        ), (argv, err)
    for path, data in inputs.items():
        assert path.read_bytes() == data, f"{path} changed: {argv}"
    if limit is not None:
        # a hang: CPU time past the limit + 5 s (a loop), or wall-clock time
        # far past it (a process blocked); a process merely starved on a
        # loaded machine (the offline run is nice'd) is neither
        took, cpu = time.monotonic() - began, _children_cpu() - cpu_before
        assert cpu < limit + 5 and took < limit + 60, (argv, took, cpu, code, err[-300:])


@pytest.mark.slow
@settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=not RANDOM,
    database=None,
    suppress_health_check=list(HealthCheck),
    phases=PHASES,
)
@given(data=st.data())
def test_hostile_options_and_functions_get_a_clean_answer(tmp_path_factory, data):
    folder = tmp_path_factory.mktemp("hostile")
    in_process = data.draw(st.integers(0, 49), label="process?") != 0
    if in_process:
        kind, source = data.draw(functions_files(), label="functions")
    else:
        kind = data.draw(st.sampled_from(sorted(PROCESS_KINDS)), label="functions")
        source = PROCESS_KINDS[kind]
    d, p, fns = _setup(folder, source)
    TALLY[kind.split(" ")[0] if in_process else f"process: {kind}"] += 1
    timeout = data.draw(st.sampled_from(TIMEOUTS if in_process else ["1", "2"]), label="timeout")
    if kind.startswith("loop") and timeout not in ("0.5", "2", "1e-9", "1", "2"):
        timeout = "0.5"  # a loop at import ends by the deadline alone
    other = folder / "other.dot"
    out = _path(data.draw(st.sampled_from(PATHS), label="-o"), folder, d, p, fns, other)
    dot = (
        _path(
            data.draw(st.sampled_from(PATHS), label="--dot"), folder, d, p, fns, folder / "out.txt"
        )
        if data.draw(st.booleans(), label="dot?")
        else None
    )
    argv = ["plan", d, p, "--functions", fns, "--timeout", timeout, "-o", out]
    argv += ["--dot", dot] if dot is not None else []
    inputs = {x: x.read_bytes() for x in (d, p, fns)}
    began, cpu_before = time.monotonic(), _children_cpu()
    if in_process:
        r = run_htn(*argv, timeout=120)
        limit = None
    else:
        r = run_htn_process(*argv, timeout=120)
        limit = float(timeout) + 3  # the watchdog's grace, and a process's start
    _check(r, argv, inputs, limit, began, kind, cpu_before)


FIELDS = {
    "seed": ["x", 1.5, -1, 2**70, None, [], True],
    "plan_index": [0, -1, 2, 1.0, "1", None, True, 10**12],
    "faults": [3, [], {"slip": 1}, "effect=2", "effect=x", "nosuch=0.5", None, "e" * 10_000],
    "retries": [[1], {"!go": -1}, {"!go": "x"}, {"!nosuch": 1}, "x", None, {"": 1}],
    "replan": ["yes", 1, None, []],
    "robot": [None, 3, "", "nosuch", "symbolic" * 100],
    "plan": [None, 3, "", "/nonexistent", ["a"], "x\x00y"],
    "plan_sha256": [7, "0" * 64, "xyz", None],
    "domain": [None, 3, "/nonexistent"],
    "problem": [3, "/nonexistent"],
    "domain_sha256": ["0" * 64, 5],
    "functions": ["/nonexistent", 3],
    "functions_sha256": ["0" * 64, "g" * 64],
}


@pytest.fixture(scope="module")
def logged(tmp_path_factory):
    """A real log of a symbolic run (its plan made with a functions file)."""
    folder = tmp_path_factory.mktemp("logged")
    d, p, fns = _setup(folder, GOOD)
    plan, log = folder / "plan.txt", folder / "run.jsonl"
    assert run_htn("plan", d, p, "--functions", fns, "-o", plan).returncode == 0
    r = run_htn("run", plan, "--robot", "symbolic", "--functions", fns, "--log", log, "-q")
    assert r.returncode == 0, r.stderr
    return folder, fns, log.read_text()


@pytest.mark.slow
@settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=not RANDOM,
    database=None,
    suppress_health_check=list(HealthCheck),
    phases=PHASES,
)
@given(data=st.data())
def test_edited_logs_get_a_clean_answer(logged, data):
    folder, fns, text = logged
    lines = text.splitlines()
    header = json.loads(lines[0])
    how = data.draw(
        st.sampled_from(["field", "field", "field", "drop", "cut", "bytes"]), label="edit"
    )
    if how == "field":
        field = data.draw(st.sampled_from(sorted(FIELDS)), label="field")
        header[field] = data.draw(st.sampled_from(FIELDS[field]), label="value")
        edited = "\n".join([json.dumps(header), *lines[1:]]) + "\n"
    elif how == "drop":
        header.pop(data.draw(st.sampled_from(sorted(header)), label="dropped"))
        edited = "\n".join([json.dumps(header), *lines[1:]]) + "\n"
    else:
        at = data.draw(st.integers(0, len(lines[0])), label="at")
        edited = text[:at] if how == "cut" else text[:at] + "\udcff" + text[at:]
    log = folder / f"edited-{data.draw(st.integers(0, 10**9), label='name')}.jsonl"
    log.write_bytes(edited.encode("utf-8", "surrogateescape"))
    given_functions = data.draw(st.booleans(), label="--functions?")
    argv = ["run", "--from-log", log, "-q", *(["--functions", fns] if given_functions else [])]
    TALLY[f"log {how}"] += 1
    r = run_htn(*argv, timeout=120)
    _check(r, argv, {fns: fns.read_bytes()}, None, time.monotonic(), how)
    if r.returncode == 2 and how == "field" and field in ("seed", "plan_index", "replan"):
        assert r.stderr.startswith(f"{log}:1: "), r.stderr
