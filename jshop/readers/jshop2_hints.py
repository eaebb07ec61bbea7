"""What a JSHOP2 syntax error most likely means, in a newcomer's words.

:mod:`htn.jshop.readers.lark_errors` asks :func:`hint` when neither an
unknown keyword nor a parenthesis explains a syntax error. Each hint reads
the token the parser stopped at and the lists open around it
(:func:`htn.jshop.readers.parens.open_lists`), and names the form the manual
expects there: an operator (manual 3.9), a method's branches (3.10), a domain's
list of elements (3.11), a problem's state and task list (3.12), comments (3.14).
"""

from __future__ import annotations

import re

from lark.exceptions import UnexpectedCharacters, UnexpectedToken

from htn.jshop.language.errors import HtnError

from .lark_errors import at_offset


def hint(text: str, file: str, e, at: int, stack: list):
    """An :class:`HtnError` saying what is wrong at offset ``at``, or None."""
    if isinstance(e, UnexpectedCharacters):
        return _character(text, file, at)
    if not isinstance(e, UnexpectedToken) or not stack:
        return None
    for rule in (
        _operator_name,
        _head_not_a_list,
        _primitive_in_precondition,
        _missing_part,
        _elements_not_in_a_list,
        _problem_lists,
    ):
        found = rule(text, file, e, at, stack)
        if found is not None:
            return found
    return None


def _character(text: str, file: str, at: int):
    c = text[at]
    if c == "#" or text.startswith("//", at):
        return at_offset(
            text,
            file,
            at,
            f"unexpected '{'//' if c == '/' else c}': comments "
            "start with ';' in JSHOP2 (manual 3.14)",
        )
    if c in "\"'":
        return at_offset(
            text,
            file,
            at,
            f"unexpected {c!r}: JSHOP2 has no strings; a "
            "symbol is letters, digits, '-', '_', '?' and '!' (manual 3.1)",
        )
    return None


def _tok(e) -> str:
    return str(e.token)


def _in(stack: list, head: str):
    """The innermost open list whose first word is ``head``, and its depth."""
    for k in range(len(stack) - 1, -1, -1):
        if stack[k].head == head:
            return stack[k], k
    return None, -1


def _name_after(text: str, lst, keyword: str) -> str:
    m = re.compile(rf"\(\s*{re.escape(keyword)}\s*\(\s*([^\s()]+)", re.I).match(text, lst.start)
    return m.group(1) if m else "?"


def _operator_name(text, file, e, at, stack):
    """``(:operator (brew ?c) ...)``: an operator's name starts with '!'; and
    a method's head is a compound task, without '!'."""
    kind = e.token.type
    if kind == "NAME" and "OPNAME" in e.expected and "NAME" not in e.expected:
        return at_offset(
            text,
            file,
            at,
            f"an operator's name starts with '!': write (!{_tok(e)} ...) (manual 3.9)",
        )
    if (
        kind == "OPNAME"
        and len(stack) >= 2
        and stack[-2].head == ":method"
        and stack[-2].items == [":method", "("]
    ):
        return at_offset(
            text,
            file,
            at,
            f"a method's head is a compound task, named without "
            f"'!': '{_tok(e)}' is an operator's name (manual 3.10)",
        )
    return None


def _head_not_a_list(text, file, e, at, stack):
    """``(:method go ?r ?to ...)``: the head is a list."""
    top = stack[-1]
    if (
        top.head in (":method", ":operator")
        and top.items == [top.head]
        and e.token.type in ("NAME", "OPNAME", "VAR")
    ):
        what = "method" if top.head == ":method" else "operator"
        return at_offset(
            text,
            file,
            at,
            f"a{'n' if what == 'operator' else ''} {what}'s head "
            f"is a list: write ({top.head} ({_tok(e)} ...) ...)",
        )
    return None


def _branch_lists(method) -> int:
    """Lists after a method's head (branch labels are words, not counted)."""
    return method.items[2:].count("(")


def _primitive_in_precondition(text, file, e, at, stack):
    """A task list read as a method's precondition: its precondition is missing."""
    method, k = _in(stack, ":method")
    if e.token.type != "OPNAME" or method is None or k + 1 >= len(stack):
        return None
    if _branch_lists(method) % 2 == 1:  # the list holding it is a precondition
        name = _name_after(text, method, ":method")
        return at_offset(
            text,
            file,
            at,
            f"'{_tok(e)}' is a task, but this list is read as a "
            f"precondition of method {name}: a branch is a precondition and then "
            "a task list; write () before the task list for no precondition "
            "(manual 3.10)",
        )
    return None


def _missing_part(text, file, e, at, stack):
    """A ``)`` that ends an operator, a method branch or a problem too soon."""
    if e.token.type != "RPAR":
        return None
    top = stack[-1]
    if top.head == ":operator":
        n = len(top.items[2:])  # lists, nil or a variable (manual 3.14)
        name = _name_after(text, top, ":operator")
        if n < 3:
            lists = "no list" if n == 0 else "only one list" if n == 1 else "only two lists"
            return HtnError(
                f"operator {name} has {lists} after its head; an operator "
                "needs three: a precondition, a delete list and an add list "
                "(write () for an empty one; manual 3.9)",
                file,
                top.line,
                top.col,
            )
    if top.head == ":method":
        name = _name_after(text, top, ":method")
        if top.items[1:2] != ["("]:
            return None
        n = _branch_lists(top)
        if n % 2 == 1 or n == 0:
            what = "no branch" if n == 0 else "a precondition without its task list"
            return HtnError(
                f"method {name} ends with {what}: each branch is [name] "
                "precondition task-list (write () for an empty one; manual 3.10)",
                file,
                top.line,
                top.col,
            )
    if top.head == "defproblem":
        lists = top.items.count("(")
        if lists < 2:
            return HtnError(
                "a problem needs an initial state and a task list: (defproblem "
                "NAME DOMAIN (ATOM ...) (TASK ...)) (manual 3.12)",
                file,
                top.line,
                top.col,
            )
    return None


def _elements_not_in_a_list(text, file, e, at, stack):
    """``(defdomain d (:operator ...) ...)``: the elements go in one list."""
    if (
        len(stack) >= 2
        and stack[-2].head == "defdomain"
        and len(stack[-2].items) == 3
        and stack[-1].items == []
        and _tok(e).lower() in (":operator", ":method", ":-")
    ):
        return at_offset(
            text,
            file,
            at,
            "a domain's operators, methods and axioms go in one "
            "list: (defdomain NAME ((:operator ...) (:method ...))) (manual 3.11)",
        )
    return None


def _problem_lists(text, file, e, at, stack):
    """``(defproblem p d (at a b) (task))``: the state and the task list are
    lists of atoms and of tasks."""
    if len(stack) < 2 or stack[-2].head != "defproblem" or e.token.type not in ("NAME", "OPNAME"):
        return None
    if stack[-1].items:
        return None
    which = stack[-2].items[3:].count("(")  # lists before this one (name, domain, then lists)
    what = (
        "the initial state is a list of atoms"
        if which % 2 == 1
        else "the task list is a list of tasks"
    )
    return at_offset(
        text,
        file,
        at,
        f"{what}: write (({_tok(e)} ...) ...), with a "
        "parenthesis around the whole list (manual 3.12)",
    )
