"""A fast reader of well-formed HDDL, without lark (whose import and first
parse cost more than planning a small instance).

It reads what :mod:`htn.jshop.readers.hddl` reads, into the same model, with
the same positions and spellings: the text is cut into tokens and nested
lists by one regular expression, and each list is read as the grammar
(``hddl.lark``) says. It accepts only input it is sure of: any token, list or
definition that is not plainly well-formed (a syntax error, a token lark would
split differently, a name defined twice, a cost that is not a number, lists
nested deeper than :data:`MAX_DEPTH`) raises :class:`Fallback`, and
:func:`htn.jshop.readers.load.parse_text` then reads the text with lark, which
gives the located error message. ``tests/jshop/test_hddl_fast.py`` checks that
both readers give equal models on every HDDL file of the corpus and on
mutants of them.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var

from .hddl_model import (
    ActionDef,
    EffectCost,
    EffectForall,
    EffectWhen,
    Exists,
    HDomain,
    HProblem,
    MethodDef,
    Network,
    Param,
    Subtask,
    TaskDef,
)

MAX_DEPTH = 200  # deeper lists go to lark, which does not recurse

# a chunk between spaces (lark's WS: [ \t\f\r\n]+, not \s), a parenthesis, a comment
_PIECE = re.compile(r"[^ \t\f\r\n();]+|[()]|;[^\n\r]*")
_BREAK = re.compile(r"\n")
# hddl.lark's patterns without re.I (0.5 ms each to compile: Unicode case
# folding); the non-ASCII letters re.I admits (the Kelvin sign) go to lark
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_\-]*\Z")
_VAR = re.compile(r"\?[A-Za-z_][A-Za-z0-9_\-]*\Z")
_NUMBER = re.compile(r"[0-9]+(\.[0-9]+)?\Z")
_REQUIREMENT = re.compile(r":[A-Za-z][A-Za-z0-9_\-]*\Z")
_GD = frozenset(("and", "or", "not", "imply", "exists", "forall"))
_EFFECT = frozenset(("and", "not", "forall", "when", "increase"))
_ORDERED = frozenset((":ordered-subtasks", ":ordered-tasks"))
_UNORDERED = frozenset((":subtasks", ":tasks"))


class Fallback(Exception):
    """The text is not plainly well-formed HDDL: read it with lark."""


class Tok:
    __slots__ = ("text", "line", "col")

    def __init__(self, text: str, line: int, col: int):
        self.text, self.line, self.col = text, line, col


class Lst(list):  # type: ignore[type-arg]
    """A parenthesised list: its items, and where its "(" is."""

    __slots__ = ("line", "col")
    line: int
    col: int


def lists(text: str, tokens: Callable[[str, int, int, str], list[Tok]] | None = None) -> Lst:
    """The one top-level list of ``text``. ``tokens(chunk, line, col,
    after)``: the tokens a chunk of text between spaces, parentheses and
    comments is (``after``: the character that follows it); HDDL's by
    default. Spaces are skipped by the pattern, lines found by the breaks."""
    split = tokens or _hddl_tokens
    stack: list[Lst] = [Lst()]
    top = stack[0]
    breaks = [m.start() for m in _BREAK.finditer(text)]
    breaks.append(len(text))
    line, start, next_break = 1, 0, breaks[0]  # start: the offset of the line's first character
    for m in _PIECE.finditer(text):
        at = m.start()
        while at > next_break:
            start = next_break + 1
            next_break = breaks[line]
            line += 1
        piece = m.group()
        first = piece[0]
        if first == "(":
            lst = Lst()
            lst.line, lst.col = line, at - start + 1
            top.append(lst)
            stack.append(lst)
            top = lst
            if len(stack) > MAX_DEPTH:
                raise Fallback("nested too deep")
        elif first == ")":
            if len(stack) == 1:
                raise Fallback("unbalanced")
            stack.pop()
            top = stack[-1]
        elif first == ";":
            continue  # a comment
        elif tokens is None and first != "-":
            top.append(Tok(piece, line, at - start + 1))  # HDDL's one token
        else:
            top.extend(split(piece, line, at - start + 1, text[m.end() : m.end() + 1]))
    if len(stack) != 1 or len(stack[0]) != 1 or not isinstance(stack[0][0], Lst):
        raise Fallback("not one list")
    return stack[0][0]


def _hddl_tokens(atom: str, line: int, col: int, after: str) -> list[Tok]:
    out = []
    while atom[0] == "-" and len(atom) > 1:  # "-t" is "-" then t, as lark lexes it
        out.append(Tok("-", line, col))
        atom, col = atom[1:], col + 1
    out.append(Tok(atom, line, col))
    return out


def _kw(x: Any) -> str | None:
    """The lower-cased text of a token, None for a list."""
    return x.text.lower() if isinstance(x, Tok) else None


class Reader:
    def __init__(self, file: str):
        self.file = file
        self.spelling: dict[str, str] = {}

    def pos(self, x: Any) -> S.Pos:
        return S.Pos(self.file, x.line, x.col)

    # ---------------------------------------------------------------- tokens
    def name(self, x: Any) -> str:
        if not isinstance(x, Tok) or not _NAME.match(x.text):
            raise Fallback("a name")
        low = x.text.lower()
        self.spelling.setdefault(low, x.text)
        return low

    def arg(self, x: Any) -> Any:
        if isinstance(x, Tok) and _VAR.match(x.text):
            return Var(x.text.lower())
        return self.name(x)

    def typed(self, items: list[Any], var: bool) -> list[Param]:
        out: list[Param] = []
        pending: list[tuple[str, S.Pos]] = []
        k = 0
        while k < len(items):
            x = items[k]
            if isinstance(x, Tok) and x.text == "-":
                if k + 1 == len(items):
                    raise Fallback("a type")
                t = items[k + 1]
                if isinstance(t, Lst):
                    if len(t) < 2 or _kw(t[0]) != "either":
                        raise Fallback("either")
                    types = tuple(self.name(n) for n in t[1:])
                    where = self.pos(t[1])
                else:
                    types, where = (self.name(t),), self.pos(t)
                out += [Param(n, types, p, where) for n, p in pending]
                pending = []
                k += 2
                continue
            if var:
                if not (isinstance(x, Tok) and _VAR.match(x.text)):
                    raise Fallback("a variable")
                pending.append((x.text.lower(), self.pos(x)))
            else:
                pending.append((self.name(x), self.pos(x)))
            k += 1
        return out + [Param(n, ("object",), p) for n, p in pending]

    def atom(self, lst: Any) -> S.Atom:
        if not isinstance(lst, Lst) or not lst:
            raise Fallback("an atom")
        name = self.name(lst[0])
        return S.Atom(name, tuple(self.arg(a) for a in lst[1:]), self.pos(lst))

    # ---------------------------------------------------------------- formulas
    def gd(self, lst: Any) -> Any:
        if not isinstance(lst, Lst):
            raise Fallback("a formula")
        if not lst:
            return S.And([], self.pos(lst))
        head, n, at = _kw(lst[0]), len(lst), self.pos(lst)
        if head == "=" and n == 3:
            return S.Equal(self.arg(lst[1]), self.arg(lst[2]), at)
        if head not in _GD:
            return self.atom(lst)
        if head == "and":
            return S.And([self.gd(x) for x in lst[1:]], at)
        if head == "or":
            return S.Or([self.gd(x) for x in lst[1:]], at)
        if head == "not" and n == 2:
            return S.Not(self.gd(lst[1]), at)
        if head == "imply" and n == 3:
            a, b = self.gd(lst[1]), self.gd(lst[2])
            return S.Or([S.Not(a, at), b], at)
        if head in ("exists", "forall") and n == 3 and isinstance(lst[1], Lst):
            # the model's quantifiers hold Params: hddl_domain makes them variables
            params: Any = self.typed(lst[1], True)
            body = self.gd(lst[2])
            return (
                Exists(params, body, at) if head == "exists" else S.ForAll(params, None, body, at)
            )
        raise Fallback(head)

    def effect(self, lst: Any) -> Any:
        if not isinstance(lst, Lst):
            raise Fallback("an effect")
        if not lst:
            return []
        head, n, at = _kw(lst[0]), len(lst), self.pos(lst)
        if head not in _EFFECT:
            return self.atom(lst)
        if head == "and":
            out: list[Any] = []
            for x in lst[1:]:
                e = self.effect(x)
                out += e if isinstance(e, list) else [e]
            return out
        if head == "not" and n == 2:
            return S.Not(self.atom(lst[1]), at)
        if head == "forall" and n == 3 and isinstance(lst[1], Lst):
            params = self.typed(lst[1], True)
            return EffectForall(params, self.effect(lst[2]), at)
        if head == "when" and n == 3:
            cond = self.gd(lst[1])
            return EffectWhen([], cond, self.effect(lst[2]), at)
        if head == "increase" and n == 3 and isinstance(lst[1], Lst) and len(lst[1]) == 1:
            if self.name(lst[1][0]) == "total-cost":
                cost = lst[2]
                if isinstance(cost, Tok) and _NUMBER.match(cost.text):
                    return EffectCost(float(cost.text), at)
        raise Fallback(head)

    # ---------------------------------------------------------------- task networks
    def task_atom(self, lst: Any) -> Subtask:
        if not isinstance(lst, Lst) or not lst or not isinstance(lst[0], Tok):
            raise Fallback("a task")
        name = self.name(lst[0])
        return Subtask(None, name, tuple(self.arg(a) for a in lst[1:]), self.pos(lst[0]))

    def subtask(self, lst: Any) -> Subtask:
        if isinstance(lst, Lst) and len(lst) == 2 and isinstance(lst[1], Lst):
            label = self.name(lst[0])
            task = self.task_atom(lst[1])
            task.label = label
            return task
        return self.task_atom(lst)

    def order(self, lst: Any) -> tuple[str, str, S.Pos]:
        if not isinstance(lst, Lst) or len(lst) != 3 or not all(isinstance(x, Tok) for x in lst):
            raise Fallback("an order")
        if lst[0].text in ("<", ">"):
            op, a, b = lst[0], self.name(lst[1]), self.name(lst[2])
        elif lst[1].text in ("<", ">"):
            a, op, b = self.name(lst[0]), lst[1], self.name(lst[2])
        else:
            raise Fallback("an order")
        if op.text == ">":
            a, b = b, a
        return (a, b, self.pos(op))

    def _list(self, lst: Any, item: Any) -> list[Any]:
        """``()``, ``(and item*)`` or one item."""
        if isinstance(lst, Lst) and not lst:
            return []
        if isinstance(lst, Lst) and _kw(lst[0]) == "and":
            return [item(x) for x in lst[1:]]
        return [item(lst)]

    def network(self, items: list[Any]) -> Network:
        """``subtasks? ordering? constraints?`` from the keyword/value pairs."""
        net = Network(pos=self.pos(items[0]) if items else None)
        k, stage = 0, 0
        while k < len(items):
            key = _kw(items[k])
            if k + 1 == len(items):
                raise Fallback("a value")
            value = items[k + 1]
            if stage < 1 and (key in _ORDERED or key in _UNORDERED):
                net.ordered, net.subtasks = key in _ORDERED, self._list(value, self.subtask)
                stage = 1
            elif stage < 2 and key in (":ordering", ":order"):
                net.ordering = self._list(value, self.order)
                stage = 2
            elif stage < 3 and key == ":constraints":
                net.constraints = self.gd(value)
                stage = 3
            else:
                raise Fallback("a task network")
            k += 2
        return net

    def _options(self, items: list[Any], keys: tuple[str, ...]) -> dict[str, Any]:
        """``:key value`` pairs in the grammar's order, each at most once."""
        out: dict[str, Any] = {}
        k = 0
        for key in keys:
            if k < len(items) and _kw(items[k]) == key:
                if k + 1 == len(items):
                    raise Fallback("a value")
                out[key] = items[k + 1]
                k += 2
        if k != len(items):
            raise Fallback("an option")
        return out

    def _params(self, lst: Any) -> list[Param]:
        if not isinstance(lst, Lst):
            raise Fallback("parameters")
        return self.typed(lst, True)

    # ---------------------------------------------------------------- domain
    def domain(self, top: Lst) -> HDomain:
        head = top[1]
        if len(head) != 2 or _kw(head[0]) != "domain":
            raise Fallback("(domain name)")
        d = HDomain(self.name(head[1]), file=self.file, pos=self.pos(top))
        for part in top[2:]:
            if not isinstance(part, Lst) or not part:
                raise Fallback("a domain item")
            key = _kw(part[0])
            if key == ":requirements":
                if not all(isinstance(x, Tok) and _REQUIREMENT.match(x.text) for x in part[1:]):
                    raise Fallback("requirements")
            elif key == ":types":
                for p in self.typed(part[1:], False):
                    d.types.setdefault(p.name, [])
                    d.type_pos.setdefault(p.name, p.pos)
                    for t in p.types:
                        if t != "object" or p.name != "object":
                            d.types[p.name].append(t)
                        d.types.setdefault(t, [])
            elif key == ":constants":
                d.constants += self.typed(part[1:], False)
            elif key == ":predicates":
                for pdef in part[1:]:
                    if not isinstance(pdef, Lst) or not pdef:
                        raise Fallback("a predicate")
                    pname = self.name(pdef[0])
                    d.predicates[pname] = self.typed(pdef[1:], True)
            elif key == ":functions":
                self.functions(part[1:])
            elif key == ":task":
                self.define(d.tasks, self.task_def(part))
            elif key == ":method":
                d.methods.append(self.method(part))
            elif key == ":action":
                self.define(d.actions, self.action(part))
            else:
                raise Fallback("a domain item")
        d.spelling = self.spelling
        return d

    def define(self, table: dict[str, Any], item: Any) -> None:
        if item.name in table:
            raise Fallback("defined twice")  # lark's reader says where
        table[item.name] = item

    def functions(self, items: list[Any]) -> None:
        k = 0
        while k < len(items):
            f = items[k]
            if not isinstance(f, Lst) or not f:
                raise Fallback("a function")
            self.name(f[0])
            self.typed(f[1:], True)
            k += 1
            if k < len(items) and isinstance(items[k], Tok) and items[k].text == "-":
                if k + 1 == len(items):
                    raise Fallback("a type")
                self.name(items[k + 1])
                k += 2

    def task_def(self, part: Lst) -> TaskDef:
        if len(part) < 2:
            raise Fallback("a task")
        name, at = self.name(part[1]), self.pos(part[1])
        opts = self._options(part[2:], (":parameters", ":precondition", ":effect"))
        params = self._params(opts[":parameters"]) if ":parameters" in opts else []
        if ":precondition" in opts:
            self.gd(opts[":precondition"])
        if ":effect" in opts:
            self.effect(opts[":effect"])
        return TaskDef(name, params, at)

    def method(self, part: Lst) -> MethodDef:
        if len(part) < 6 or _kw(part[2]) != ":parameters" or _kw(part[4]) != ":task":
            raise Fallback("a method")
        name, at = self.name(part[1]), self.pos(part[1])
        params = self._params(part[3])
        task = self.task_atom(part[5])
        rest = part[6:]
        pre = None
        if rest and _kw(rest[0]) == ":precondition":
            if len(rest) < 2:
                raise Fallback("a precondition")
            pre = self.gd(rest[1])
            rest = rest[2:]
        return MethodDef(name, params, task, pre, self.network(rest), at)

    def action(self, part: Lst) -> ActionDef:
        if len(part) < 2:
            raise Fallback("an action")
        name, at = self.name(part[1]), self.pos(part[1])
        opts = self._options(part[2:], (":parameters", ":precondition", ":effect"))
        params = self._params(opts[":parameters"]) if ":parameters" in opts else []
        pre = self.gd(opts[":precondition"]) if ":precondition" in opts else None
        effect = self.effect(opts[":effect"]) if ":effect" in opts else []
        return ActionDef(name, params, pre, effect, at)

    # ---------------------------------------------------------------- problem
    def problem(self, top: Lst) -> HProblem:
        head, ref = top[1], top[2] if len(top) > 2 else None
        if len(head) != 2 or _kw(head[0]) != "problem":
            raise Fallback("(problem name)")
        name = self.name(head[1])
        if not isinstance(ref, Lst) or len(ref) != 2 or _kw(ref[0]) != ":domain":
            raise Fallback("(:domain name)")
        p = HProblem(name, self.name(ref[1]), file=self.file, pos=self.pos(top))
        for part in top[3:]:
            if not isinstance(part, Lst) or not part:
                raise Fallback("a problem item")
            key = _kw(part[0])
            if key == ":requirements":
                if not all(isinstance(x, Tok) and _REQUIREMENT.match(x.text) for x in part[1:]):
                    raise Fallback("requirements")
            elif key == ":objects":
                p.objects += self.typed(part[1:], False)
            elif key == ":htn":
                rest = part[1:]
                params: list[Param] = []
                if rest and _kw(rest[0]) == ":parameters":
                    if len(rest) < 2:
                        raise Fallback("parameters")
                    params = self._params(rest[1])
                    rest = rest[2:]
                p.params, p.network = params, self.network(rest)
            elif key == ":init":
                p.init += [a for a in map(self.init_item, part[1:]) if a is not None]
            elif key == ":goal" and len(part) == 2:
                p.goal = self.gd(part[1])
            elif key == ":metric" and len(part) == 3:
                self.name(part[1])
                self.metric_expr(part[2])
            else:
                raise Fallback("a problem item")
        p.spelling = self.spelling
        return p

    def init_item(self, x: Any) -> S.Atom | None:
        if isinstance(x, Lst) and x and _kw(x[0]) == "=":
            if len(x) != 3 or not isinstance(x[1], Lst) or not x[1]:
                raise Fallback("(= (f ...) n)")
            self.name(x[1][0])
            for a in x[1][1:]:
                self.arg(a)
            if not (isinstance(x[2], Tok) and _NUMBER.match(x[2].text)):
                raise Fallback("a number")
            return None  # numeric fluents (total-cost = 0): nothing to keep
        return self.atom(x)

    def metric_expr(self, x: Any) -> None:
        if isinstance(x, Lst):
            if not x:
                raise Fallback("a metric")
            self.name(x[0])
            for a in x[1:]:
                self.arg(a)
        elif not _NUMBER.match(x.text):
            self.name(x)


def parse_model(text: str, file: str = "<string>") -> HDomain | HProblem:
    """The model of an HDDL domain or problem; :class:`Fallback` where the
    text is not plainly well-formed."""
    top = lists(text)
    if len(top) < 2 or _kw(top[0]) != "define" or not isinstance(top[1], Lst) or not top[1]:
        raise Fallback("(define ...)")
    reader = Reader(file)
    kind = _kw(top[1][0])
    if kind == "domain":
        return reader.domain(top)
    if kind == "problem":
        return reader.problem(top)
    raise Fallback("(define ...)")
