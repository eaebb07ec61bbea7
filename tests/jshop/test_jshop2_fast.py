"""The fast JSHOP2 reader (:mod:`htn.jshop.readers.jshop2_fast`) against
lark's (:mod:`htn.jshop.readers.jshop2`): on every JSHOP2 file of the corpus
and of this repository both give the same domain or problem (positions and
variable numbers included), and on mutants the fast reader either gives
lark's or gives up (lark then reads the text and locates the error): it
never accepts what lark refuses, and never reads anything differently."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import FunctionTable
from htn.jshop.readers import jshop2, jshop2_fast, load
from htn.jshop.readers.source import decode_source

from conftest import ROOT, SHARED
from fuzz_mutations import text_mutant

CORPUS = SHARED / "corpus" / "jshop2"


def _files() -> list[Path]:
    here = [*(ROOT / "domains").glob("*.jshop"), *(ROOT / "problems").glob("*.jshop")]
    corpus = [
        p
        for p in CORPUS.glob("*/*")
        if p.is_file() and p.suffix not in (".txt", ".json", ".md") and "plans" not in p.name
    ]
    return sorted(here + corpus)


def _same_or_gives_up(text: str, file: str) -> str:
    """'same' or 'fallback'; fails on a disagreement."""
    try:
        want, error = repr(jshop2.parse_jshop2(text, file, FunctionTable())), None
    except HtnError as e:
        want, error = None, str(e)
    try:
        got = jshop2_fast.parse_jshop2(text, file, FunctionTable())
    except jshop2_fast.Fallback:
        return "fallback"
    assert error is None, f"the fast reader accepts what lark refuses: {error}"
    assert repr(got) == want
    return "same"


def test_every_jshop2_file_reads_the_same_with_both_readers():
    files = _files()
    assert len(files) >= 11  # the repository's own domains and problems at least
    outcomes = {
        f"{f.parent.name}/{f.name}": _same_or_gives_up(
            decode_source(f.read_bytes(), str(f)), str(f)
        )
        for f in files
    }
    # only the two that call functions no file gives (lark says which) go to lark
    gave_up = {k for k, v in outcomes.items() if v == "fallback"}
    assert gave_up <= {"freecell/freecell", "test/test"}, outcomes


INSERTS = ["(", ")", "?", "!", ";", "\n", " ", "x", "-", "+", "nil", "and", ":unordered", ".", "1"]


def _mutant(text: str, rng: random.Random) -> str:
    return text_mutant(text, rng, INSERTS)


@pytest.mark.parametrize(
    "name", ["domains/domestic.jshop", "domains/kitchen.jshop", "problems/bring_object.jshop"]
)
def test_a_mutant_reads_as_lark_reads_it_or_goes_to_lark(name):
    text = (ROOT / name).read_text()
    rng = random.Random(name)
    seen = {"same": 0, "fallback": 0}
    for _ in range(150):
        t = text
        for _ in range(rng.randrange(1, 3)):
            t = _mutant(t, rng)
        try:
            load.check_nesting(t, name)
        except HtnError:
            continue  # unbalanced: refused before either reader
        seen[_same_or_gives_up(t, name)] += 1
    assert seen["same"] > 20 and seen["fallback"] > 10, seen  # both ways were taken


@pytest.mark.parametrize(
    "text",
    [
        "(defproblem p d ((at a.b)) ((t)))",  # lark lexes a.b apart
        "(defproblem p d ((at 1-2)) ((t)))",
        "(defproblem p d ((member a b)) ((t)))",  # a keyword as a name
        "(defproblem p d ((at ?x)) ((t)))",  # a variable in the state: lark says where
        "(defdomain d ((:method (t) ((call undefined ?x)) ())))",
        # the Kelvin sign, which lark's case-insensitive names take for a k
        "(defproblem p d ((at \u212aitchen)) ((t)))",
        "(defproblem p d ((at ?\u212a)) ((t)))",
    ],
)
def test_what_it_is_not_sure_of_goes_to_lark(text):
    with pytest.raises(jshop2_fast.Fallback):
        jshop2_fast.parse_jshop2(text, "x.jshop")


def test_plain_planning_does_not_import_lark():
    import subprocess
    import sys

    code = (
        "import sys, htn;"
        f"htn.plan({str(ROOT / 'domains/domestic.jshop')!r},"
        f" {str(ROOT / 'problems/bring_object.jshop')!r}).__next__();"
        "print('lark' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.stdout.strip() == "False", out.stderr


def test_plan_steps_read_the_same_with_both_readers():
    lines = {
        line.strip()
        for f in CORPUS.glob("*/plans-first*.txt")
        for line in f.read_text().splitlines()
        if line.startswith("(")
    }
    lines |= {"(!a 1.5 -2 nil (x y . z))", "(:immediate !go ?x)", "(!t (call + 1 2))"}
    rng = random.Random(3)
    mutants = [_mutant(t, rng) for t in sorted(lines) for _ in range(3)]
    seen = {"same": 0, "fallback": 0}
    for text in sorted(lines) + mutants:
        try:
            want = repr(jshop2.parse_step(text, "p.txt", 7))
        except HtnError as e:
            want = str(e)
        try:
            got = repr(jshop2_fast.parse_step(text, "p.txt", 7))
        except jshop2_fast.Fallback:
            seen["fallback"] += 1
            continue
        assert got == want, text
        seen["same"] += 1
    assert seen["same"] > len(lines) and seen["fallback"] > 10, seen
