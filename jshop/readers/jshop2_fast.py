"""A fast reader of well-formed JSHOP2, without lark (whose import and parse
cost more than planning a small problem: 35 ms of the 91 ms ``htn plan``
took on the domestic robot's problem).

It reads what :mod:`htn.jshop.readers.jshop2` reads, into the same syntax
objects, with the same positions: the text is cut into tokens and nested
lists (:func:`htn.jshop.readers.hddl_fast.lists`), and each list is read as
``jshop2.lark`` says, as the :class:`~htn.jshop.readers.jshop2.Builder`
builds it (a rule's position is its first token's, parentheses and
keywords included). It accepts only what it is sure of: a chunk of text
that is not exactly one of the grammar's tokens, a keyword where a name
stands (lark's contextual lexer reads some of them as names, which is not
worth guessing), a list that is not plainly the construct its place asks
for, an undefined function or comparator, a variable in an initial state:
all raise :class:`Fallback`, and :func:`htn.jshop.readers.load.parse_text`
then reads the text with lark, which gives the located error message (or
the model). ``tests/jshop/test_jshop2_fast.py`` checks that both readers
give equal models on every JSHOP2 file here and on mutants of them.
"""

from __future__ import annotations

import re
from functools import partial
from typing import Any

from htn.jshop.language import syntax as S
from htn.jshop.language.functions import STDLIB_JAVA_NAMES, FunctionTable, arity_error
from htn.jshop.language.terms import NIL, CallTerm, Var, make_list, variables
from htn.jshop.language.walk import walk_tasks

from .hddl_fast import Fallback, Lst, Tok, _kw
from .hddl_fast import lists as _lists
from .numbering import index_var, number_axiom, number_method, number_operator

# the grammar's patterns (jshop2.lark), ASCII letters spelled out: compiled
# with re.I they cost 0.5 ms each at start-up (Unicode case folding of the
# ranges), and the few non-ASCII letters re.I lets in go to lark
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9\-_?!]*\Z")
_OPNAME = re.compile(r"!(?!=)[A-Za-z0-9\-_?!]*\Z")
_VAR = re.compile(r"\?[A-Za-z0-9\-_?!]*\Z")
_NUM = re.compile(r"[-+]?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?\Z")
_STDFN = frozenset(("<=", ">=", "!=", "<", ">", "=", "/", "*", "^"))
KEYWORDS = frozenset(
    (
        "defdomain",
        "defproblem",
        "and",
        "or",
        "not",
        "imply",
        "forall",
        "assign",
        "call",
        "nil",
        "member",
        ":method",
        ":operator",
        ":protection",
        ":first",
        ":sort-by",
        ":unordered",
        ":immediate",
        ":-",
        ".",
    )
)


def parse_jshop2(text: str, file: str = "<string>", functions: FunctionTable | None = None):
    """A JSHOP2 domain or problem read from ``text`` (nesting checked by the
    caller); raises :class:`Fallback` where lark's reader must read it."""
    top = lists(text)
    reader = _Reader(file, functions or FunctionTable())
    head = _kw(top[0]) if top else None
    if head == "defdomain":
        return reader.domain(top)
    if head == "defproblem":
        return reader.problem(top)
    raise Fallback("not a domain or a problem")


_SEPARATORS = frozenset(" \t\f\r\n)")


def parse_step(text: str, file: str = "<plan>", line: int = 1) -> S.TaskAtom:
    """One plan step such as ``(!move_base jenny home kitchen)``, as
    :func:`htn.jshop.readers.jshop2.parse_step` reads it (positions on the
    step's own line 1); raises :class:`Fallback` where that must read it."""
    return _Reader(file, FunctionTable()).task_atom(lists(text))


def lists(text: str) -> Lst:
    """The one top-level list of ``text``; every chunk of it must be exactly
    one token of the grammar (else lark would cut it otherwise)."""
    return _lists(text, _tokens)


def _tokens(chunk: str, line: int, col: int, after: str) -> list[Tok]:
    if chunk in ("-", "+"):  # a function only before a space or ")"
        if after not in _SEPARATORS:
            raise Fallback("a sign")
    elif not _one_token(chunk):
        raise Fallback("not one token")
    return [Tok(chunk, line, col)]


def _one_token(chunk: str) -> bool:
    return (
        chunk.lower() in KEYWORDS
        or chunk in _STDFN
        or _NAME.match(chunk) is not None
        or _OPNAME.match(chunk) is not None
        or _VAR.match(chunk) is not None
        or _NUM.match(chunk) is not None
    )


def _is_name(x: Any) -> bool:
    return isinstance(x, Tok) and _NAME.match(x.text) is not None and x.text.lower() not in KEYWORDS


def _is_var(x: Any) -> bool:
    return isinstance(x, Tok) and _VAR.match(x.text) is not None


class _Reader:
    def __init__(self, file: str, functions: FunctionTable):
        self.file = file
        self.functions = functions
        self.method_count = 0
        self.axiom_count = 0

    def pos(self, x: Any) -> S.Pos:
        return S.Pos(self.file, x.line, x.col)

    # ---------------------------------------------------------------- terms
    def name(self, x: Any) -> str:
        if not _is_name(x):
            raise Fallback("a name")
        return str(x.text.lower())

    def var(self, x: Any) -> Var:
        if not _is_var(x):
            raise Fallback("a variable")
        return Var(x.text.lower())

    def term(self, x: Any) -> Any:
        if isinstance(x, Tok):
            t = x.text
            if _VAR.match(t):
                return Var(t.lower())
            low = t.lower()
            if low == "nil":
                return NIL
            if _NUM.match(t):
                return float(t)
            return self.name(x)
        if x and _kw(x[0]) == "call":
            return self.call(x)
        dots = [k for k, y in enumerate(x) if _kw(y) == "."]
        if not dots:
            return tuple(self.term(y) for y in x)
        if dots != [len(x) - 2]:
            raise Fallback("a dotted list")
        return make_list([self.term(y) for y in x[:-2]], self.term(x[-1]))

    def call(self, x: Lst) -> CallTerm:
        if len(x) < 2 or not isinstance(x[1], Tok):
            raise Fallback("a call")
        tok = x[1]
        name = tok.text.lower()
        if not (_is_name(tok) or tok.text in _STDFN or name in ("member", "-", "+")):
            raise Fallback("a function")
        args = tuple(self.term(y) for y in x[2:])
        func = self.functions.lookup(name)
        if func is None or arity_error(name, len(args)):
            raise Fallback("a call lark reports")
        return CallTerm(STDLIB_JAVA_NAMES.get(name, tok.text), func, args, self.pos(x))

    # ---------------------------------------------------------------- logic
    def atom(self, x: Any) -> S.Atom | S.VarAtom:
        if _is_var(x):
            return S.VarAtom(Var(x.text.lower()), self.pos(x))
        if not isinstance(x, Lst) or not x or not _is_name(x[0]):
            raise Fallback("an atom")
        return S.Atom(x[0].text.lower(), tuple(self.term(y) for y in x[1:]), self.pos(x))

    def expr(self, x: Any) -> Any:
        if isinstance(x, Tok):
            if _kw(x) == "nil":
                return S.And([], self.pos(x))
            if _is_var(x):
                return S.VarAtom(Var(x.text.lower()), self.pos(x))
            raise Fallback("an expression")
        if not x:
            return S.And([], self.pos(x))
        head = x[0]
        kw = _kw(head)
        if kw == "and":
            return self._and([self.expr(y) for y in x[1:]], x)
        if kw == "or":
            if len(x) < 2:
                raise Fallback("or")
            items = [self.expr(y) for y in x[1:]]
            return items[0] if len(items) == 1 else S.Or(items, self.pos(x))
        if kw == "not":
            if len(x) != 2:
                raise Fallback("not")
            return S.Not(self.expr(x[1]), self.pos(x))
        if kw == "imply":
            if len(x) != 3:
                raise Fallback("imply")
            p = self.pos(x)
            return S.Or([S.Not(self.expr(x[1]), p), self.expr(x[2])], p)
        if kw == "forall":
            if len(x) != 4:
                raise Fallback("forall")
            return S.ForAll(self.forall_vars(x[1]), self.expr(x[2]), self.expr(x[3]), self.pos(x))
        if kw == "assign":
            if len(x) != 3:
                raise Fallback("assign")
            return S.Assign(self.var(x[1]), self.term(x[2]), self.pos(x))
        if kw == "call":
            return S.CallExpr(self.call(x), self.pos(x))
        if _is_name(head):
            return S.Atom(kw, tuple(self.term(y) for y in x[1:]), self.pos(x))  # type: ignore[arg-type]
        if isinstance(head, Lst) or kw == "nil" or _is_var(head):
            return self._and([self.expr(y) for y in x], x)
        raise Fallback("an expression")

    def _and(self, items: list, x: Lst) -> Any:
        return items[0] if len(items) == 1 else S.And(items, self.pos(x))

    def forall_vars(self, x: Any) -> list[Var]:
        if _kw(x) == "nil":
            return []
        if not isinstance(x, Lst):
            raise Fallback("forall variables")
        return [self.var(y) for y in x]

    def precondition(self, x: Any) -> S.Precondition:
        kw = _kw(x[0]) if isinstance(x, Lst) and x else None
        if kw == ":first":
            if len(x) != 2:
                raise Fallback(":first")
            return S.Precondition(self.expr(x[1]), first=True, pos=self.pos(x))
        if kw == ":sort-by":
            if len(x) == 3:
                var, cmp, expr = self.var(x[1]), "<", self.expr(x[2])
            elif len(x) == 4 and isinstance(x[2], Tok):
                var, expr = self.var(x[1]), self.expr(x[3])
                cmp = x[2].text.lower()
                if not (_is_name(x[2]) or x[2].text in _STDFN or cmp in ("member", "-", "+")):
                    raise Fallback("a comparator")
                if cmp not in ("<", ">") and self.functions.comparator(cmp) is None:
                    raise Fallback("an undefined comparator")
            else:
                raise Fallback(":sort-by")
            return S.Precondition(expr, sort_var=var, comparator=cmp, pos=self.pos(x))
        return S.Precondition(self.expr(x), pos=self.pos(x))

    # ---------------------------------------------------------------- tasks
    def task_atom(self, x: Lst) -> S.TaskAtom:
        immediate = bool(x) and _kw(x[0]) == ":immediate"
        items = x[1:] if immediate else x
        if not items or not isinstance(items[0], Tok):
            raise Fallback("a task")
        name = items[0]
        if not (_is_name(name) or _OPNAME.match(name.text)):
            raise Fallback("a task name")
        args = tuple(self.term(y) for y in items[1:])
        return S.TaskAtom(name.text.lower(), args, immediate, self.pos(name))

    def tasklist(self, x: Any) -> S.TaskList:
        if _kw(x) == "nil":
            return S.TaskList([], True, self.pos(x))
        if not isinstance(x, Lst):
            raise Fallback("a task list")
        ordered = not (x and _kw(x[0]) == ":unordered")
        out: list[S.TaskAtom | S.TaskList] = []
        for y in x if ordered else x[1:]:
            if isinstance(y, Tok):
                out.append(self.tasklist(y))
            elif not y or isinstance(y[0], Lst) or _kw(y[0]) in ("nil", ":unordered"):
                out.append(self.tasklist(y))
            else:
                out.append(self.task_atom(y))
        return S.TaskList(out, ordered, self.pos(x))

    # ---------------------------------------------------------------- effects
    def effects(self, x: Any) -> S.Effects:
        if _kw(x) == "nil":
            return S.Effects(items=[])
        if _is_var(x):
            return S.Effects(var=Var(x.text.lower()))
        if not isinstance(x, Lst):
            raise Fallback("effects")
        return S.Effects(items=[self.effect(y) for y in x])

    def effect(self, x: Any) -> Any:
        kw = _kw(x[0]) if isinstance(x, Lst) and x else None
        if kw == ":protection":
            if len(x) != 2:
                raise Fallback(":protection")
            return S.Protection(self.atom(x[1]), self.pos(x))
        if kw == "forall":
            if len(x) != 4:
                raise Fallback("forall")
            atoms = x[3]
            if _kw(atoms) == "nil":
                listed = []
            elif isinstance(atoms, Lst):
                listed = [self.atom(a) for a in atoms]
            else:
                raise Fallback("effect atoms")
            return S.EffectForAll(self.forall_vars(x[1]), self.expr(x[2]), listed, self.pos(x))
        return self.atom(x)

    # ---------------------------------------------------------------- elements
    def operator(self, x: Lst) -> S.Operator:
        if len(x) not in (5, 6) or not isinstance(x[1], Lst) or not x[1]:
            raise Fallback(":operator")
        name = x[1][0]
        if not (isinstance(name, Tok) and _OPNAME.match(name.text)):
            raise Fallback("an operator name")
        args = tuple(self.term(y) for y in x[1][1:])
        head = S.TaskAtom(name.text.lower(), args, False, self.pos(name))
        pre, dele, add = self.precondition(x[2]), self.effects(x[3]), self.effects(x[4])
        cost = self.term(x[5]) if len(x) == 6 else 1.0
        op = S.Operator(head, pre, dele, add, cost, pos=self.pos(x))
        op.nvars = number_operator(op)
        return op

    def _branches(self, items: list, with_tasks: bool) -> list[tuple]:
        """``(label token or None, precondition item, task list item)``."""
        out = []
        k, step = 0, 2 if with_tasks else 1
        while k < len(items):
            label = items[k] if _is_name(items[k]) else None
            if label is not None:
                k += 1
            if k + step > len(items):
                raise Fallback("a branch")
            out.append((label, *items[k : k + step]))
            k += step
        if not out:
            raise Fallback("no branch")
        return out

    def method(self, x: Lst) -> S.Method:
        if len(x) < 4 or not isinstance(x[1], Lst) or not x[1]:
            raise Fallback(":method")
        name = x[1][0]
        args = tuple(self.term(y) for y in x[1][1:])
        branches = []
        for k, (label, pre, tasks) in enumerate(self._branches(x[2:], True)):
            p = self.precondition(pre)
            text = label.text if label is not None else f"Method{self.method_count}Branch{k}"
            where = self.pos(label) if label is not None else p.pos
            branches.append(S.Branch(text, p, self.tasklist(tasks), where))
        head = S.TaskAtom(self.name(name), args, False, self.pos(name))
        m = S.Method(head, branches, index=self.method_count, pos=self.pos(x))
        self.method_count += 1
        m.nvars = number_method(m)
        return m

    def axiom(self, x: Lst) -> S.Axiom:
        if len(x) < 3:
            raise Fallback(":-")
        head = self.atom(x[1])
        if not isinstance(head, S.Atom):
            raise Fallback("an axiom's head")
        branches = []
        for k, (label, pre) in enumerate(self._branches(x[2:], False)):
            p = self.precondition(pre)
            text = label.text if label is not None else f"Axiom{self.axiom_count}Branch{k}"
            where = self.pos(label) if label is not None else p.pos
            branches.append(S.AxiomBranch(text, p, where))
        ax = S.Axiom(head, branches, pos=self.pos(x))
        self.axiom_count += 1
        ax.nvars = number_axiom(ax)
        return ax

    def domain(self, x: Lst) -> S.Domain:
        if len(x) != 3 or not isinstance(x[2], Lst):
            raise Fallback("defdomain")
        d = S.Domain(self.name(x[1]), file=self.file, pos=self.pos(x))
        for e in x[2]:
            kw = _kw(e[0]) if isinstance(e, Lst) and e else None
            if kw == ":operator":
                op = self.operator(e)
                d.operators.setdefault(op.name, []).append(op)
            elif kw == ":method":
                m = self.method(e)
                d.methods.setdefault(m.name, []).append(m)
            elif kw == ":-":
                ax = self.axiom(e)
                d.axioms.setdefault(ax.head.pred, []).append(ax)
            else:
                raise Fallback("a domain element")
        return d

    # ---------------------------------------------------------------- problem
    def problem(self, x: Lst) -> S.Problem:
        if len(x) < 5 or (len(x) - 3) % 2:
            raise Fallback("defproblem")
        instances = []
        for k in range(3, len(x), 2):
            state_item, tasks = x[k], x[k + 1]
            if _kw(state_item) == "nil":
                state: list = []
            elif isinstance(state_item, Lst):
                state = [self.atom(a) for a in state_item]
            else:
                raise Fallback("an initial state")
            for a in state:
                if isinstance(a, S.VarAtom) or variables(a.args, []):
                    raise Fallback("a variable in an initial state")
            tl = self.tasklist(tasks)
            walk_tasks(tl, partial(index_var, {}))  # variables numbered per instance
            instances.append(S.ProblemInstance(state, tl, self.pos(state_item)))
        return S.Problem(
            self.name(x[1]),
            self.name(x[2]),
            instances,
            file=self.file,
            pos=self.pos(x),
            domain_pos=self.pos(x[2]),
        )
