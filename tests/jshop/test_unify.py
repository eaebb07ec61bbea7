"""Terms, substitution, one-way unification and JSHOP2 printing."""

from __future__ import annotations

import pytest

from htn.jshop.language.functions import STDLIB
from htn.jshop.language.terms import NIL, CallTerm, Dotted, Var, make_list, subst, term_str, unify


def V(i, name=None):
    return Var(name or f"?v{i}", i)


def test_pattern_variable_binds_and_must_then_match():
    env = [None, None]
    assert unify((V(0), V(0)), ("a", "a"), env) and env[0] == "a"
    assert not unify((V(1), V(1)), ("a", "b"), [None, None])


def test_variable_on_the_term_side_matches_anything_and_binds_nothing():
    env = [None]
    assert unify(V(0), Var("?other", 0), env)
    assert env == [None]
    assert unify("a", Var("?x", 3), [None])
    assert unify(("a", "b"), ("a", Var("?x", 0)), [None])


def test_constants_numbers_and_types():
    assert unify("a", "a", [])
    assert not unify("a", "b", [])
    assert unify(2.0, 2.0, [])
    assert not unify(2.0, "2", [])
    env = [1.0]
    assert not unify(V(0), "1", env)  # bound variable must equal, type included


def test_lists_and_dotted_lists():
    env = [None, None]
    assert unify(make_list([V(0)], V(1)), ("a", "b", "c"), env)
    assert env == ["a", ("b", "c")]
    env = [None]
    assert unify(make_list(["a"], V(0)), make_list(["a", "b"], "c"), env)
    assert env[0] == Dotted(("b",), "c")
    assert not unify(("a", "b"), ("a",), [])
    assert make_list(["a"], ("b", "c")) == ("a", "b", "c")
    assert make_list(["a"], make_list(["b"], "c")) == Dotted(("a", "b"), "c")


def test_subst_evaluates_call_terms_once_ground():
    plus = CallTerm("StdLib.plus", STDLIB["+"], (V(0), 1.0))
    assert subst(plus, [2.0]) == 3.0
    still = subst(plus, [None])
    assert isinstance(still, CallTerm) and term_str(still).startswith("(CALL StdLib.plus")
    nested = CallTerm("StdLib.mult", STDLIB["*"], (2.0, plus))
    assert subst((V(1), nested), [4.0, "x"]) == ("x", 10.0)


def test_call_term_in_a_pattern_is_evaluated_before_unifying():
    two = CallTerm("StdLib.plus", STDLIB["+"], (1.0, 1.0))
    assert unify(two, 2.0, [])
    assert not unify(two, 3.0, [])


@pytest.mark.parametrize(
    "value,text",
    [
        (0.0, "0.0"),
        (2.0, "2.0"),
        (-12.5, "-12.5"),
        (0.4, "0.4"),
        (123456.0, "123456.0"),
        (1e7, "1.0E7"),
        (12345678.9, "1.23456789E7"),
        (0.0001, "1.0E-4"),
        (0.001, "0.001"),
        (67.5, "67.5"),
        (-0.0, "-0.0"),
    ],
)
def test_numbers_print_as_java_doubles(value, text):
    assert term_str(value) == text


def test_printing_lists_nil_dotted_and_variables():
    assert term_str(NIL) == "NIL"
    assert term_str(("a", (1.0, "b"))) == "(a (1.0 b))"
    assert term_str(make_list([("x", "y"), "a", "b"], "c")) == "((x y) a b . c)"
    assert term_str(Var("?out", 3)) == "VAR3"
