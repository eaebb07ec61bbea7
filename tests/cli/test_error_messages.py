"""A newcomer's slips in a domain of their own get plain words, located (issue 19).

The coffee robot (3 operators, 2 methods), in JSHOP2 and in HDDL, with one
slip at a time: each gets one line ``file:line:col: message`` that says what
is wrong where it is (an unclosed list at its '(', an unknown keyword with the
nearest one), not the parser's view of the token after it.
"""

from __future__ import annotations

import contextlib
import io

import pytest

from coffee import COFFEE, COFFEE_HDDL, MORNING, MORNING_HDDL


def _plan(tmp_path, domain, problem, ext="jshop"):
    from htn.cli.main import main

    d, p = tmp_path / f"coffee.{ext}", tmp_path / f"morning.{ext}"
    d.write_text(domain)
    p.write_text(problem)
    out, err = io.StringIO(), io.StringIO()
    code = 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main(["plan", str(d), str(p), "-f", "jshop"])
        except SystemExit as exc:
            code = exc.code
    return code, out.getvalue(), err.getvalue()


def _swap(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def test_the_coffee_robot_plans(tmp_path):
    for domain, problem, ext in ((COFFEE, MORNING, "jshop"), (COFFEE_HDDL, MORNING_HDDL, "hddl")):
        code, out, err = _plan(tmp_path, domain, problem, ext)
        assert code == 0 and err == "", err
        assert "(!brew robby mug)" in out


# (name, domain, problem, file:line:col, the message) -- exit 2
ERRORS = [
    (
        "unclosed list: at its '('",
        _swap(
            COFFEE, "((full ?cup) (holding ?robot ?cup)))", "((full ?cup) (holding ?robot ?cup))"
        ),
        MORNING,
        "coffee.jshop:8:3",
        "this '(' is never closed; a ')' at the end of line 11 would close it",
    ),
    (
        "an extra ')'",
        _swap(COFFEE, "((at ?robot ?to)))\n", "((at ?robot ?to))))\n"),
        MORNING,
        "coffee.jshop:6:23",
        "one ')' too many: this one closes the '(' at 2:19, but line 8 below is laid out inside",
    ),
    (
        "a ')' that closes nothing",
        COFFEE.rstrip() + ")\n",
        MORNING,
        "coffee.jshop:24:96",
        "this ')' closes nothing",
    ),
    (
        "unknown keyword",
        _swap(COFFEE, "(:operator (!brew", "(:opertor (!brew"),
        MORNING,
        "coffee.jshop:8:4",
        "unknown keyword ':opertor'; did you mean :operator?",
    ),
    (
        "a misspelled defdomain",
        _swap(COFFEE, "(defdomain", "(defdomian"),
        MORNING,
        "coffee.jshop:2:2",
        "unknown word 'defdomian'; did you mean defdomain?",
    ),
    (
        "empty domain file",
        "",
        MORNING,
        "coffee.jshop:1:1",
        "empty file, expected (defdomain NAME (...))",
    ),
    (
        "a problem file of comments",
        COFFEE,
        "; to do\n",
        "morning.jshop:1:1",
        "nothing but comments in this file, expected (defproblem NAME DOMAIN (ATOM ...) (TASK ...))",
    ),
    (
        "operator name without '!'",
        _swap(COFFEE, "(:operator (!brew", "(:operator (brew"),
        MORNING,
        "coffee.jshop:8:15",
        "an operator's name starts with '!': write (!brew ...) (manual 3.9)",
    ),
    (
        "operator with a missing list",
        _swap(COFFEE, "    ((empty ?cup))\n    ((full", "    ((full"),
        MORNING,
        "coffee.jshop:8:3",
        "operator !brew has only two lists after its head; an operator needs three: a "
        "precondition, a delete list and an add list (write () for an empty one; manual 3.9)",
    ),
    (
        "method without a task list",
        _swap(
            COFFEE,
            "    ((go ?robot kitchen) (!brew ?robot ?cup) (go ?robot ?place) "
            "(!hand ?robot ?cup ?person)))))",
            "    )))",
        ),
        MORNING,
        "coffee.jshop:22:3",
        "method serve ends with a precondition without its task list: each branch is [name] "
        "precondition task-list",
    ),
    (
        "method without a precondition",
        _swap(COFFEE, "    ((empty ?cup) (at ?person ?place))\n", ""),
        MORNING,
        "coffee.jshop:23:27",
        "'!brew' is a task, but this list is read as a precondition of method serve",
    ),
    (
        "method head without parentheses",
        _swap(COFFEE, "(:method (go ?robot ?to)", "(:method go ?robot ?to"),
        MORNING,
        "coffee.jshop:18:12",
        "a method's head is a list: write (:method (go ...) ...)",
    ),
    (
        "method named like an operator",
        _swap(COFFEE, "(:method (serve", "(:method (!serve"),
        MORNING,
        "coffee.jshop:22:13",
        "a method's head is a compound task, named without '!'",
    ),
    (
        "elements not in one list",
        _swap(
            _swap(COFFEE, "(defdomain coffee (", "(defdomain coffee"), "?person)))))", "?person))))"
        ),
        MORNING,
        "coffee.jshop:3:4",
        "a domain's operators, methods and axioms go in one list",
    ),
    (
        "a '#' comment",
        _swap(COFFEE, "; A coffee", "# A coffee"),
        MORNING,
        "coffee.jshop:1:1",
        "unexpected '#': comments start with ';' in JSHOP2 (manual 3.14)",
    ),
    (
        "problem for a misspelled domain",
        COFFEE,
        _swap(MORNING, "morning coffee", "morning cofee"),
        "morning.jshop:1:21",
        "problem 'morning' is for domain 'cofee', but",
    ),
    (
        "problem without a task list",
        COFFEE,
        "(defproblem morning coffee\n  ((at robby dock) (empty mug) (at ada office)))\n",
        "morning.jshop:1:1",
        "a problem needs an initial state and a task list",
    ),
    (
        "initial state without its list",
        COFFEE,
        _swap(MORNING, "((at robby dock) (empty mug) (at ada office))", "(at robby dock)"),
        "morning.jshop:2:4",
        "the initial state is a list of atoms: write ((at ...) ...)",
    ),
    (
        "task list without its list",
        COFFEE,
        _swap(MORNING, "((serve robby ada))", "(serve robby ada)"),
        "morning.jshop:3:4",
        "the task list is a list of tasks: write ((serve ...) ...)",
    ),
    (
        "a task in the problem with the wrong number of arguments",
        COFFEE,
        _swap(MORNING, "(serve robby ada)", "(serve robby)"),
        "morning.jshop:3:5",
        "'serve' takes 2 arguments, given 1 (it is (serve ?robot ?person) at ",
    ),
    (
        "an add-list variable nothing binds",
        _swap(COFFEE, "((has ?person ?cup))", "((has ?someone ?cup))"),
        MORNING,
        "coffee.jshop:16:6",
        "operator !hand adds (has ...) with ?someone unbound: neither its head nor its "
        "precondition binds it",
    ),
]

HDDL_ERRORS = [
    (
        "unclosed list",
        _swap(COFFEE_HDDL, "(at ?who ?p))\n    :ordered", "(at ?who ?p)\n    :ordered"),
        MORNING_HDDL,
        "coffee.hddl:34:19",
        "this '(' is never closed; a ')' at the end of line 34 would close it",
    ),
    (
        "an extra ')'",
        _swap(COFFEE_HDDL, "(at ?r ?to)))\n  (:action brew", "(at ?r ?to))))\n  (:action brew"),
        MORNING_HDDL,
        "coffee.hddl:12:51",
        "one ')' too many: this one closes the '(' at 1:1",
    ),
    (
        "unknown keyword",
        _swap(
            COFFEE_HDDL,
            ":precondition (at ?r ?from)\n    :effect",
            ":precondtion (at ?r ?from)\n    :effect",
        ),
        MORNING_HDDL,
        "coffee.hddl:11:5",
        "unknown keyword ':precondtion'; did you mean :precondition?",
    ),
    (
        "unknown keyword in the problem",
        COFFEE_HDDL,
        _swap(MORNING_HDDL, "(:init", "(:int"),
        "morning.hddl:4:4",
        "unknown keyword ':int'; did you mean :init?",
    ),
    (
        "empty domain file",
        "",
        MORNING_HDDL,
        "coffee.hddl:1:1",
        "empty file, expected (define (domain NAME) ...)",
    ),
    (
        "empty problem file",
        COFFEE_HDDL,
        "",
        "morning.hddl:1:1",
        "empty file, expected (define (problem NAME) (:domain DOMAIN) ...)",
    ),
]


@pytest.mark.parametrize(
    "name,domain,problem,where,message,ext",
    [(*e, "jshop") for e in ERRORS] + [(*e, "hddl") for e in HDDL_ERRORS],
    ids=[e[0] for e in ERRORS] + ["hddl: " + e[0] for e in HDDL_ERRORS],
)
def test_a_slip_gets_plain_words_where_it_is(tmp_path, name, domain, problem, where, message, ext):
    code, out, err = _plan(tmp_path, domain, problem, ext)
    assert code == 2, err
    first = err.splitlines()[0]
    assert first.startswith(f"{tmp_path}/{where}: "), first
    assert message in first, first
    assert "Traceback" not in err


# legal JSHOP2 that cannot do what was meant: a located warning, then no plan
WARNINGS = [
    (
        "a variable without '?'",
        _swap(COFFEE, "(:operator (!brew ?robot ?cup)", "(:operator (!brew ?robot cup)"),
        "coffee.jshop:8:15",
        "operator !brew: 'cup' in (!brew ?robot cup) is a constant, while ?cup "
        "is a variable of this operator; did you mean ?cup?",
    ),
    (
        "a variable without '?' in a precondition",
        _swap(COFFEE, "((at ?robot kitchen) (empty ?cup))", "((at robot kitchen) (empty ?cup))"),
        "coffee.jshop:9:6",
        "'robot' in (at robot kitchen) is a constant",
    ),
    (
        "a task with the wrong number of arguments",
        _swap(COFFEE, "(!brew ?robot ?cup) (go", "(!brew ?cup) (go"),
        "coffee.jshop:24:27",
        "'!brew' takes 2 arguments, given 1; branch Method1Branch0 of serve can never succeed "
        "(it is (!brew ?robot ?cup) at ",
    ),
]


@pytest.mark.parametrize("name,domain,where,message", WARNINGS, ids=[w[0] for w in WARNINGS])
def test_a_slip_that_is_legal_gets_a_located_warning(tmp_path, name, domain, where, message):
    code, out, err = _plan(tmp_path, domain, MORNING)
    assert code == 1 and out == "", err
    first = err.splitlines()[0]
    assert first.startswith(f"{tmp_path}/{where}: warning: "), first
    assert message in first, first


def test_a_constant_named_like_a_variable_is_not_always_a_slip(tmp_path):
    # a type tag beside its variable, or a constant other elements use as well
    tagged = _swap(
        COFFEE,
        "((at ?robot kitchen) (empty ?cup))",
        "((at ?robot kitchen) (empty ?cup) (kind ?cup cup))",
    )
    tagged = _swap(
        tagged, "(at ?person ?place))\n    ((go", "(at ?person ?place) (kind ?cup cup))\n    ((go"
    )
    code, out, err = _plan(
        tmp_path, tagged, _swap(MORNING, "(empty mug)", "(empty mug) (kind mug cup)")
    )
    assert code == 0 and "warning" not in err, err
