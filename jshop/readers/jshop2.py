"""Read JSHOP2 domain and problem files into :mod:`htn.jshop.language.syntax` objects.

The grammar lives in ``jshop2.lark``; one :class:`Builder` transformer turns the
parse tree into domain objects. Variables are numbered per domain element in the
order JSHOP2's parser meets them (manual 5.1.1), because that index is what an
unbound variable prints as (``VAR<n>``).

Reading a file (its encoding, its nesting) is :mod:`htn.jshop.readers.source`;
choosing the reader by content is :mod:`htn.jshop.readers.load`.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from lark import Lark, Token
from lark.exceptions import UnexpectedInput, VisitError
from lark.visitors import Transformer_NonRecursive

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import STDLIB_JAVA_NAMES, FunctionTable, arity_error
from htn.jshop.language.terms import NIL, CallTerm, Var, make_list, variables
from htn.jshop.language.walk import walk_tasks

from . import jshop2_hints, lark_errors
from .lark_compat import with_meta
from .numbering import index_var, number_axiom, number_method, number_operator
from .source import check_nesting

GRAMMAR = Path(__file__).with_name("jshop2.lark")


@lru_cache(maxsize=1)
def _lark() -> Lark:
    lark_errors.check_lark()
    return Lark(
        GRAMMAR.read_text(),
        parser="lalr",
        propagate_positions=True,
        maybe_placeholders=False,
        start=["start", "task_atom"],
        cache=True,
    )


_TOKEN_NAMES = {
    "LPAR": "'('",
    "RPAR": "')'",
    "NAME": "a symbol",
    "OPNAME": "an operator name (!name)",
    "VAR": "a variable (?name)",
    "NUM": "a number",
    "$END": "end of file",
}


class Builder(Transformer_NonRecursive):
    """Turns the Lark tree into syntax objects (method names = rule names);
    it walks the tree with a stack, so nesting costs no Python recursion."""

    def __init__(self, file: str, functions: FunctionTable):
        super().__init__()
        self.file = file
        self.functions = functions
        self.method_count = 0
        self.axiom_count = 0

    def pos(self, meta) -> S.Pos | None:
        if getattr(meta, "empty", True):
            return None
        return S.Pos(self.file, meta.line, meta.column)

    def tpos(self, tok: Token) -> S.Pos:
        return S.Pos(self.file, tok.line, tok.column)

    # ---------------------------------------------------------------- terms
    def var(self, items):
        return Var(str(items[0]).lower())

    def symbol(self, items):
        return str(items[0]).lower()

    def number(self, items):
        return float(str(items[0]))

    def nil(self, items):
        return NIL

    def list_term(self, items):
        return tuple(items)

    def dotted_term(self, items):
        *head, _dot, tail = items
        return make_list(head, tail)

    def function(self, items):
        return items[0]

    @with_meta
    def call(self, meta, items):
        tok, *args = items
        name = str(tok).lower()
        func = self.functions.lookup(name)
        if func is None:
            raise HtnError.at(
                self.tpos(tok),
                f"undefined function '{tok}' in call (give its Python file with --functions)",
            )
        why = arity_error(name, len(args))
        if why:
            raise HtnError.at(self.pos(meta), why)
        shown = STDLIB_JAVA_NAMES.get(name, str(tok))
        return CallTerm(shown, func, tuple(args), self.pos(meta))

    # ---------------------------------------------------------------- logic
    @with_meta
    def atom(self, meta, items):
        name, *args = items
        return S.Atom(str(name).lower(), tuple(args), self.pos(meta))

    def var_atom(self, items):
        return S.VarAtom(Var(str(items[0]).lower()), self.tpos(items[0]))

    @with_meta
    def and_expr(self, meta, items):
        if len(items) == 1:
            return items[0]
        return S.And(list(items), self.pos(meta))

    @with_meta
    def or_expr(self, meta, items):
        if len(items) == 1:
            return items[0]
        return S.Or(list(items), self.pos(meta))

    @with_meta
    def not_expr(self, meta, items):
        return S.Not(items[0], self.pos(meta))

    @with_meta
    def imply_expr(self, meta, items):
        # JSHOP2 compiles (imply Y Z) to (or (not Y) Z)
        y, z = items
        return S.Or([S.Not(y, self.pos(meta)), z], self.pos(meta))

    def forall_vars(self, items):
        return [Var(str(t).lower()) for t in items]

    @with_meta
    def forall_expr(self, meta, items):
        vs, cond, then = items
        return S.ForAll(vs, cond, then, self.pos(meta))

    @with_meta
    def assign_expr(self, meta, items):
        return S.Assign(Var(str(items[0]).lower()), items[1], self.pos(meta))

    @with_meta
    def call_expr(self, meta, items):
        return S.CallExpr(items[0], self.pos(meta))

    @with_meta
    def precondition(self, meta, items):
        return S.Precondition(items[0], pos=self.pos(meta))

    @with_meta
    def first_pre(self, meta, items):
        return S.Precondition(items[0], first=True, pos=self.pos(meta))

    @with_meta
    def sort_pre(self, meta, items):
        var = Var(str(items[0]).lower())
        if len(items) == 3:
            cmp_tok, expr = items[1], items[2]
            cmp = str(cmp_tok).lower()
            if cmp not in ("<", ">") and self.functions.comparator(cmp) is None:
                raise HtnError.at(
                    self.tpos(cmp_tok),
                    f"undefined comparator '{cmp_tok}' (give its Python file with --functions)",
                )
        else:
            cmp, expr = "<", items[1]
        return S.Precondition(expr, sort_var=var, comparator=cmp, pos=self.pos(meta))

    # ---------------------------------------------------------------- tasks
    @with_meta
    def task_atom(self, meta, items):
        immediate = False
        if isinstance(items[0], Token) and items[0].type == "IMMEDIATE":
            immediate = True
            items = items[1:]
        name, *args = items
        return S.TaskAtom(str(name).lower(), tuple(args), immediate, self.tpos(name))

    @with_meta
    def tasklist(self, meta, items):
        ordered = True
        if items and isinstance(items[0], Token) and items[0].type == "UNORDERED":
            ordered = False
            items = items[1:]
        return S.TaskList(list(items), ordered, self.pos(meta))

    # ---------------------------------------------------------------- effects
    def effect_list(self, items):
        return S.Effects(items=list(items))

    def effect_var(self, items):
        return S.Effects(var=Var(str(items[0]).lower()))

    @with_meta
    def protection(self, meta, items):
        return S.Protection(items[0], self.pos(meta))

    def effect_atoms(self, items):
        return list(items)

    @with_meta
    def effect_forall(self, meta, items):
        vs, cond, atoms = items
        return S.EffectForAll(vs, cond, atoms, self.pos(meta))

    # ---------------------------------------------------------------- elements
    @with_meta
    def operator(self, meta, items):
        name, *rest = items
        # rest: head terms..., precondition, del, add, [cost]
        idx = next(i for i, x in enumerate(rest) if isinstance(x, S.Precondition))
        args, (pre, dele, add, *cost) = tuple(rest[:idx]), rest[idx:]
        head = S.TaskAtom(str(name).lower(), args, False, self.tpos(name))
        op = S.Operator(head, pre, dele, add, cost[0] if cost else 1.0, pos=self.pos(meta))
        op.nvars = number_operator(op)
        return op

    @with_meta
    def branch(self, meta, items):
        label = str(items[0]) if isinstance(items[0], Token) else None
        pre, tasks = items[-2], items[-1]
        return S.Branch(label, pre, tasks, self.pos(meta))

    @with_meta
    def method(self, meta, items):
        name = items[0]
        args = tuple(x for x in items[1:] if not isinstance(x, S.Branch))
        branches = [x for x in items[1:] if isinstance(x, S.Branch)]
        for k, b in enumerate(branches):
            if b.label is None:
                b.label = f"Method{self.method_count}Branch{k}"
        head = S.TaskAtom(str(name).lower(), args, False, self.tpos(name))
        m = S.Method(head, branches, index=self.method_count, pos=self.pos(meta))
        self.method_count += 1
        m.nvars = number_method(m)
        return m

    @with_meta
    def axiom_branch(self, meta, items):
        label = str(items[0]) if isinstance(items[0], Token) else None
        return S.AxiomBranch(label, items[-1], self.pos(meta))

    @with_meta
    def axiom(self, meta, items):
        head, *branches = items
        if isinstance(head, S.VarAtom):
            raise HtnError.at(head.pos, "an axiom's head must be an atom, not a variable")
        for k, b in enumerate(branches):
            if b.label is None:
                b.label = f"Axiom{self.axiom_count}Branch{k}"
        ax = S.Axiom(head, branches, pos=self.pos(meta))
        self.axiom_count += 1
        ax.nvars = number_axiom(ax)
        return ax

    @with_meta
    def domain(self, meta, items):
        name, *elements = items
        d = S.Domain(str(name).lower(), file=self.file, pos=self.pos(meta))
        for e in elements:
            if isinstance(e, S.Operator):
                d.operators.setdefault(e.name, []).append(e)
            elif isinstance(e, S.Method):
                d.methods.setdefault(e.name, []).append(e)
            else:
                d.axioms.setdefault(e.head.pred, []).append(e)
        return d

    # ---------------------------------------------------------------- problem
    def initial_state(self, items):
        return list(items)

    @with_meta
    def instance(self, meta, items):
        state, tasks = items
        for a in state:
            if isinstance(a, S.VarAtom) or variables(a.args, []):
                raise HtnError.at(a.pos, "atoms in the initial state must be ground")
        scope: dict = {}
        walk_tasks(tasks, lambda v: index_var(scope, v))
        return S.ProblemInstance(state, tasks, self.pos(meta))

    @with_meta
    def problem(self, meta, items):
        name, dname, *instances = items
        return S.Problem(
            str(name).lower(),
            str(dname).lower(),
            instances,
            file=self.file,
            pos=self.pos(meta),
            domain_pos=self.tpos(dname),
        )

    def start(self, items):
        return items[0]


# ------------------------------------------------------------ variable numbering
# ------------------------------------------------------------ entry points


def parse_jshop2(text: str, file: str = "<string>", functions: FunctionTable | None = None):
    """Parse a JSHOP2 domain or problem from text (nesting checked by the
    caller, :func:`htn.jshop.readers.load.parse_text`)."""
    functions = functions or FunctionTable()
    tree = lark_errors.parse(
        _lark(), text, file, _TOKEN_NAMES, hints=jshop2_hints.hint, start="start"
    )
    try:
        return Builder(file, functions).transform(tree)
    except VisitError as e:
        if isinstance(e.orig_exc, HtnError):
            raise e.orig_exc from None
        raise


def parse_step(text: str, file: str = "<plan>", line: int = 1):
    """Parse one plan step such as ``(!move_base jenny home kitchen)``."""
    try:
        check_nesting(text, file)
    except HtnError as exc:  # the step is one line of the plan file
        raise HtnError(exc.message, file, line, exc.col) from None
    try:
        tree = _lark().parse(text, start="task_atom")
    except UnexpectedInput as e:
        raise HtnError(
            f"not a plan step: {text.strip()!r}", file, line, getattr(e, "column", 1)
        ) from e
    try:
        return Builder(file, FunctionTable()).transform(tree)
    except VisitError as e:
        if isinstance(e.orig_exc, HtnError):
            raise HtnError(e.orig_exc.message, file, line, 1) from None
        raise
