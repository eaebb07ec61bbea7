"""The fast HDDL reader (:mod:`htn.jshop.readers.hddl_fast`) against lark's
(:mod:`htn.jshop.readers.hddl`): on every HDDL file of the corpus and of this
repository both give the same model (positions and spellings included), and
on thousands of mutants the fast reader either gives lark's model or gives up
(lark then reads the text, and locates the error): it never accepts what lark
refuses, and never reads anything differently."""

from __future__ import annotations

import random
import sys
from pathlib import Path

import pytest

from htn.jshop.language.errors import HtnError
from htn.jshop.readers import hddl, hddl_fast
from htn.jshop.readers.source import decode_source

from conftest import ROOT, SHARED
from fuzz_mutations import text_mutant

CORPUS = SHARED / "corpus"


def _files() -> list[Path]:
    roots = [CORPUS, ROOT / "domains", ROOT / "problems", ROOT / "tests"]
    return sorted(
        p
        for r in roots
        if r.is_dir()
        for p in r.rglob("*")
        if p.suffix in (".hddl", ".pddl") and p.stat().st_size < 400_000
    )


def _lark(text: str, file: str):
    try:
        return repr(hddl.parse_model(text, file)), None
    except HtnError as e:
        return None, str(e)


def _same_or_gives_up(text: str, file: str) -> str:
    """'same' or 'fallback'; fails on a disagreement."""
    want, error = _lark(text, file)
    try:
        got = hddl_fast.parse_model(text, file)
    except hddl_fast.Fallback:
        return "fallback"
    assert error is None, f"the fast reader accepts what lark refuses: {error}"
    assert repr(got) == want
    lark_model = hddl.parse_model(text, file)
    assert got.spelling == lark_model.spelling
    return "same"


@pytest.mark.slow
@pytest.mark.corpus
def test_every_hddl_file_reads_the_same_with_both_readers():
    files = _files()
    if not any(CORPUS in f.parents for f in files):
        pytest.skip(f"no HDDL corpus at {CORPUS}")
    outcomes = {_same_or_gives_up(decode_source(f.read_bytes(), str(f)), str(f)) for f in files}
    assert outcomes == {"same"}  # none falls back to lark: all are plainly well-formed


INSERTS = ["(", ")", "-", "?", ";", "\n", " ", "x", "-x", "?x", "and", ":task", "\t", "\x0b", "1"]


def _mutant(text: str, rng: random.Random) -> str:
    return text_mutant(text, rng, INSERTS)


SMALL = [
    "ipc2020-to/Towers/domain.hddl",
    "ipc2020-to/Towers/pfile_05.hddl",
    "ipc2020-to/Childsnack/domain.hddl",
    "ipc2020-to/Rover-GTOHP/domain.hddl",
    "ipc-po/Ultralight-Cockpit/UL_domain.hddl",
    "ipc-po/Transport/domain.hddl",
    "ipc2023-to/Lamps/domain.hddl",
]


@pytest.mark.corpus
@pytest.mark.parametrize("name", SMALL)
def test_a_mutant_reads_as_lark_reads_it_or_goes_to_lark(name):
    path = CORPUS / name
    if not path.is_file():
        pytest.skip(f"{path} not found")
    text = path.read_text()
    rng = random.Random(name)
    seen = {"same": 0, "fallback": 0}
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 20000))  # as the command line sets it, for lark
    try:
        for _ in range(60):
            t = text
            for _ in range(rng.randrange(1, 4)):
                t = _mutant(t, rng)
            seen[_same_or_gives_up(t, str(path))] += 1
    finally:
        sys.setrecursionlimit(limit)
    assert seen["same"] > 10 and seen["fallback"] > 10, seen  # both ways were taken


def test_what_lark_lexes_apart_the_fast_reader_reads_apart_too():
    text = """(define (domain d) (:types a-b -object c)
      (:predicates (p ?x -a-b))
      (:action act :parameters (?x -c) :precondition (p ?x) :effect (not (p ?x))))"""
    assert _same_or_gives_up(text, "d.hddl") == "same"


def test_a_name_defined_twice_goes_to_lark_which_says_where():
    text = """(define (domain d) (:task t :parameters ()) (:task t :parameters ()))"""
    with pytest.raises(hddl_fast.Fallback):
        hddl_fast.parse_model(text, "d.hddl")
    with pytest.raises(HtnError, match="defined twice"):
        hddl.parse_model(text, "d.hddl")


def test_a_letter_only_case_folding_makes_ascii_goes_to_lark_which_reads_it():
    # the Kelvin sign: lark's names (case-insensitive patterns) take it for
    # a k; the fast reader's names are ASCII, so it leaves the text to lark
    text = """(define (problem p) (:domain d) (:objects \u212aitchen - room)
      (:init (at \u212aitchen)))"""
    with pytest.raises(hddl_fast.Fallback):
        hddl_fast.parse_model(text, "p.hddl")
    assert _same_or_gives_up(text, "p.hddl") == "fallback"
    assert "kitchen" in repr(hddl.parse_model(text, "p.hddl"))
