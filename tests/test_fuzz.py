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

    HTN_FUZZ_EXAMPLES=10000 HTN_FUZZ_RANDOM=1 python -m pytest tests/test_fuzz.py -s

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
from conftest import CORPUS, FUNCTIONS, ROOT, SHARED, corpus_available, run_htn
from hypothesis import HealthCheck, given, settings, strategies as st

sys.setrecursionlimit(max(sys.getrecursionlimit(), 20000))   # as htn's main() does
EXAMPLES = int(os.environ.get("HTN_FUZZ_EXAMPLES", "500"))
RANDOM = bool(os.environ.get("HTN_FUZZ_RANDOM"))
IPC = SHARED / "corpus" / "ipc2020-to"
LOCATED = re.compile(r"^[^\n]+:\d+:\d+: ")

FUNCTION_FILES = {"freecell": FUNCTIONS / "freecell.py", "test": FUNCTIONS / "test.py"}
SLOW = {"blocks-problem", "rover"}        # seconds per plan: their mutants mostly time out


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
                plans = None                    # JSHOP2 found none: nothing to validate
            cases.append((folder / stats["domain_file"], folder / stats["problem_file"],
                          FUNCTION_FILES.get(folder.name), plans))
    if IPC.is_dir():
        for folder in sorted(p for p in IPC.iterdir() if p.is_dir()):
            cases.append((folder / "domain.hddl", sorted(folder.glob("p*.hddl"))[0], None, None))
    for problem in sorted((ROOT / "problems").glob("*.jshop")):
        domain = re.search(r"\(defproblem\s+\S+\s+(\S+)", problem.read_text()).group(1)
        cases.append((ROOT / "domains" / f"{domain}.jshop", problem, None, None))
    return cases


CASES = _cases()

# what a mutation may insert: the language's pieces, and the inputs the
# audit found crashes with
TOKENS = [
    "(", ")", "((", "))", "()", "nil", "NIL", "?x", "?y", "?new", "a", "b", "0", "-1",
    "3.5", "1e400", "-0", "!op", "!!op", ":unordered", ":immediate", ":first", "and",
    "or", "not", "imply", "forall", "assign", "call", ":method", ":operator", ":-",
    ":protection", ":sort-by", "(call - )", "(call -)", "(call + ?x a)", "(call / 1 0)",
    "(call member a b)", "(call undefinedfn 1)", "(a . b)", "(?x . ?y)", ". ",
    "(not (p ?z))", "(forall (?x) (p ?x) (q ?x))", "(assign ?z (call + 1 2))",
    "(:sort-by ?x < (p ?x))", "(:sort-by ?x > (p ?x))", "(:first (p ?x))",
    "(:operator (!o ?a) () () ((r ?b)))", "(:method (m ?a) () ((!o ?a ?a)))",
    "(defproblem p other () ())", "defdomain", "defproblem", ";", "; comment\n", "\n",
    "\t", "é", "\ufeff", "\x00", "#", "\"", "'", "{", "\\",
    " ".join(f"(p{i} ?x)" for i in range(25)),
    "(" * 40 + "a" + ")" * 40,
    # HDDL
    ":parameters", ":task", ":subtasks", ":ordered-subtasks", ":ordering", "(< t1 t2)",
    "(t2 < t1)", "- object", "- undeclared_type", "(exists (?v - object) (p ?v))",
    "(when (p ?x) (not (p ?x)))", "(= ?x ?y)", "(imply (p a) (q a))", ":precondition ()",
    "(:goal (and))", "(define (domain other))",
]


@st.composite
def mutants(draw, text: str) -> bytes:
    """``text`` with one to four mutations, as bytes (some break UTF-8).
    Most mutations move whole expressions or words, so that many mutants
    get past the parser into the checks and the planner."""
    for _ in range(draw(st.integers(1, 4))):
        raw = draw(st.integers(0, 4)) == 0
        text = draw(_mutation(text) if raw else _balanced_mutation(text))
    data = text.encode("utf-8", "surrogatepass")
    if draw(st.integers(0, 39)) == 0:            # bytes that are not UTF-8
        at = draw(st.integers(0, len(data)))
        data = data[:at] + draw(st.sampled_from([b"\xff", b"\xc3", b"\xe2\x82", b"\x80"])) \
            + data[at:]
    if draw(st.integers(0, 39)) == 0:
        data = b"\xef\xbb\xbf" + data
    return data


def _mutation(text: str):
    n = len(text)
    position = st.integers(0, n)
    span = st.tuples(position, st.integers(1, 80)).map(lambda t: (t[0], min(n, t[0] + t[1])))
    words = list(re.finditer(r"[^\s()]+", text))

    def delete(s):
        return text[:s[0]] + text[s[1]:]

    def duplicate(s):
        return text[:s[1]] + text[s[0]:s[1]] + text[s[1]:]

    def insert(args):
        at, token = args
        return text[:at] + " " + token + " " + text[at:]

    def nest(args):
        (a, b), depth = args
        return text[:a] + "(" * depth + text[a:b] + ")" * depth + text[b:]

    def truncate(at):
        return text[:at]

    options = [span.map(delete), span.map(duplicate),
               st.tuples(position, st.sampled_from(TOKENS)).map(insert),
               st.tuples(span, st.sampled_from([1, 3, 200, 1001, 10_000])).map(nest),
               position.map(truncate)]
    if len(words) > 1:
        pick = st.integers(0, len(words) - 1)

        def replace(args):
            i, token = args
            w = words[i]
            return text[:w.start()] + token + text[w.end():]

        def swap(args):
            i, j = sorted(args)
            if i == j:
                return text
            a, b = words[i], words[j]
            return (text[:a.start()] + b.group() + text[a.end():b.start()] + a.group()
                    + text[b.end():])

        options += [st.tuples(pick, st.sampled_from(TOKENS + [w.group() for w in words[:50]]))
                    .map(replace), st.tuples(pick, pick).map(swap)]
    return st.one_of(options)


def _expressions(text: str) -> list[tuple[int, int]]:
    """Spans of the parenthesised expressions of ``text`` (comments ignored)."""
    spans, open_ = [], []
    for m in re.finditer(r"[()]|;[^\n]*", text):
        if m.group() == "(":
            open_.append(m.start())
        elif m.group() == ")" and open_:
            spans.append((open_.pop(), m.end()))
    return spans


def _balanced_mutation(text: str):
    """Delete, duplicate, move or replace a whole expression, or replace a
    word with another word of the same file: the result still parses."""
    spans = _expressions(text)
    words = [m.group() for m in re.finditer(r"[^\s()]+", text)] or ["a"]
    if len(spans) < 2:
        return st.just(text)
    span = st.sampled_from(spans)

    def delete(s):
        return text[:s[0]] + text[s[1]:]

    def duplicate(s):
        return text[:s[1]] + " " + text[s[0]:s[1]] + text[s[1]:]

    def replace(args):
        (a, b), (c, d) = args
        return text[:a] + text[c:d] + text[b:]

    def reword(args):
        (a, b), old, new = args
        return text[:a] + re.sub(rf"(?<![^\s(]){re.escape(old)}(?![^\s)])", lambda m: new,
                                 text[a:b], count=1) + text[b:]

    return st.one_of(span.map(delete), span.map(duplicate), st.tuples(span, span).map(replace),
                     st.tuples(span, st.sampled_from(words), st.sampled_from(words + TOKENS))
                     .map(reword))


TALLY: Counter = Counter()


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    if TALLY:
        print(f"\nfuzz: {sum(v for k, v in TALLY.items() if k.startswith('exit'))} inputs; "
              + ", ".join(f"{k} {v}" for k, v in sorted(TALLY.items())))


@pytest.mark.skipif(not CASES, reason="no example files")
@settings(max_examples=EXAMPLES, deadline=None, derandomize=not RANDOM, database=None,
          suppress_health_check=list(HealthCheck))
@pytest.mark.slow
@given(data=st.data())
def test_every_mutant_gets_a_clean_answer(tmp_path_factory, data):
    domain, problem, functions, plans = data.draw(st.sampled_from(CASES), label="example")
    which = data.draw(st.sampled_from(["domain", "problem", "both"]), label="mutate")
    folder = tmp_path_factory.mktemp("mutant")
    d, p = folder / domain.name, folder / (problem.name + ".p")
    d.write_bytes(data.draw(mutants(domain.read_text()), label="domain")
                  if which != "problem" else domain.read_bytes())
    p.write_bytes(data.draw(mutants(problem.read_text()), label="problem")
                  if which != "domain" else problem.read_bytes())
    extra = ["--functions", functions] if functions else []
    command = data.draw(st.sampled_from(["plan", "plan", "plan", "validate"] if plans
                                        else ["plan"]), label="command")
    if command == "plan":
        formats = ["jshop", "json", "text"] + (["ipc"] if domain.suffix == ".hddl" else [])
        fmt = data.draw(st.sampled_from(formats), label="format")
        how = data.draw(st.sampled_from([["-n", "1"], ["-n", "3"], ["--all"]]), label="plans")
        argv = ["plan", d, p, "-f", fmt, *how, "--timeout", "0.5", "-o", folder / "out.txt",
                *extra]
    else:
        argv = ["validate", d, p, plans, *extra]
    # run_htn fails the test (inprocess.LeakedState) if the command leaves
    # a signal blocked, a handler changed or a timer running; it forgets the
    # compiled code of each mutant (a new domain) as a process's end would
    r = run_htn(*argv)
    code, err = r.returncode, r.stderr
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, ())     # and nothing is blocked now
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
