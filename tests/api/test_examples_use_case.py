"""The examples use case (:mod:`htn.api.examples`): the bundled domains and
problems listed with their descriptions, and copied to a folder with the
checks of ``htn examples DIR`` (no file written over unless forced, never a
FIFO or device even then); nothing printed."""

from __future__ import annotations

import os

import pytest

from htn.api.examples import EXAMPLES, bundled, copy_examples, list_examples, summary
from htn.jshop.language.errors import HtnError


def test_the_bundled_examples_are_listed_domains_first_with_what_each_is():
    rows = list_examples()
    assert rows[0][0] == "domains" and rows[-1][0] == "problems"
    assert ("domains", "domestic.jshop") in [(f, n) for f, n, _ in rows]
    assert all(n.endswith(".jshop") and text for _, n, text in rows)
    files = bundled()
    assert {p.suffix for p in files} == {".jshop", ".toml"}
    assert all(p.parent.parent == EXAMPLES for p in files)


def test_a_summary_is_the_first_sentence_of_the_leading_comment(tmp_path):
    f = tmp_path / "d.jshop"
    f.write_text("; A domain after Fig. 7 of the paper. It has\n; two lines.\n(defdomain d ())\n")
    assert summary(f) == "A domain after Fig. 7 of the paper."


def test_the_examples_are_copied_and_not_written_over_unless_forced(tmp_path, capsys):
    dest = tmp_path / "mine"
    copied = copy_examples(dest)
    assert len(copied) == len(bundled())
    assert (dest / "domains" / "domestic.jshop").read_bytes() == (
        EXAMPLES / "domains" / "domestic.jshop"
    ).read_bytes()
    (dest / "domains" / "domestic.jshop").write_text("mine")
    with pytest.raises(HtnError, match=r"file\(s\) exist already.*use --force") as err:
        copy_examples(str(dest))
    assert err.value.file == str(dest)
    assert (dest / "domains" / "domestic.jshop").read_text() == "mine"
    assert copy_examples(dest, force=True) == copied
    assert (dest / "domains" / "domestic.jshop").read_text() != "mine"
    assert capsys.readouterr() == ("", "")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_is_refused_even_when_forced_before_anything_is_copied(tmp_path):
    (tmp_path / "domains").mkdir()
    os.mkfifo(tmp_path / "domains" / "kitchen.toml")
    with pytest.raises(HtnError, match="FIFO"):
        copy_examples(tmp_path, force=True)
    assert not (tmp_path / "problems").exists()


def test_htn_examples_parses_calls_the_api_and_prints():
    """Issue 35's rule for its command: ``cli/examples_cmd.py`` imports only
    ``htn.api``, ``htn.process``, the error type (and ``cli/``), and none of
    its functions is over 50 lines."""
    import ast

    from package_graph import imports_of, package_modules

    modules = package_modules()
    name = "htn.cli.examples_cmd"
    bad = [
        m
        for m in imports_of(name, modules[name], modules)
        if not m.startswith(("htn.api", "htn.process", "htn.cli"))
        and m != "htn.jshop.language.errors"
    ]
    assert not bad, f"{name} imports {bad}"
    long = [
        f.name
        for f in ast.walk(ast.parse(modules[name].read_text()))
        if isinstance(f, ast.FunctionDef) and f.end_lineno - f.lineno + 1 > 50
    ]
    assert not long, f"{name}: functions over 50 lines: {long}"
