"""Formulas and method bodies compiled for grounding (after HyperTensioN,
which compiles a domain into code).

Grounding evaluates the same formula under hundreds of thousands of
bindings (Freecell's and Minecraft's methods: 10 million walks of the
formula tree, each substituting every atom's arguments). Here a formula is
compiled once into a Python function of the binding that returns exactly
what :meth:`FormulaGrounder.walk <htn.jshop.search.ground_formulas.FormulaGrounder.walk>`
returns: an atom's argument tuple is built from its slots (``(env[2], 'n0')``),
a static predicate is a set membership, a dynamic one a lookup of its bit,
and a conjunction returns ``False`` at the first false item. What the
compiler does not specialise (``forall``, equality, arguments that are not
variables or constants) calls back the general walk, so the results are the
same; ``tests/jshop/test_compiled_grounding.py`` compares the two on IPC instances.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var
from htn.jshop.logic.codegen import define, described


class _Source:
    """The source of one compiled formula: a function per compound node."""

    def __init__(self, grounder, helpers: dict):
        self.grounder = grounder
        self.ns: dict = dict(helpers, B=grounder.bits.get, G=grounder)
        self.lines: list = []
        self.n = 0

    def const(self, value) -> str:
        name = f"k{len(self.ns)}"
        self.ns[name] = value
        return name

    def args(self, args: tuple) -> str | None:
        """A tuple expression for the atom's arguments under ``env``, or None
        when an argument is neither a variable nor a constant."""
        return _slots(args, self.const)

    def atom_test(self, e: S.Atom, negated: bool) -> list | None:
        """Lines that leave the atom's (or its negation's) value in ``x``."""
        args = self.args(e.args)
        if args is None:
            return None
        static = self.grounder.static.get(e.pred)
        if static is not None:
            return [f"x = {args} {'not in' if negated else 'in'} {self.const(static)}"]
        key = self.const(e.pred)
        if negated:
            return [f"b = B(({key}, {args}))", "x = True if b is None else ('lit', b, False)"]
        return [f"b = B(({key}, {args}))", "x = False if b is None else ('lit', b, True)"]

    def function(self, e) -> str:
        """The name of a generated function of ``env`` for ``e``."""
        name = f"f{self.n}"
        self.n += 1
        body: list = []
        if isinstance(e, S.Atom):
            test = self.atom_test(e, False)
            body = test + ["return x"] if test else [f"return G.walk({self.const(e)}, env)"]
        elif isinstance(e, S.And):
            body = ["out = []"]
            for item in e.items:
                body += self.item(item)
            body.append("return conj(out)")
        elif isinstance(e, S.Or):
            calls = ", ".join(f"{self.function(x)}(env)" for x in e.items)
            body = [f"return disj([{calls}])"]
        elif isinstance(e, S.Not):
            test = self.atom_test(e.expr, True) if isinstance(e.expr, S.Atom) else None
            body = test + ["return x"] if test else [f"return negate({self.function(e.expr)}(env))"]
        else:  # Equal, ForAll and what the walk rejects
            body = [f"return G.walk({self.const(e)}, env)"]
        self.lines.append(f"def {name}(env):")
        self.lines += ["    " + line for line in body]
        return name

    def item(self, e) -> list:
        """Lines of a conjunction's item: return False when it is false, append
        it to ``out`` unless it is True."""
        test = self.atom_test(e, False) if isinstance(e, S.Atom) else None
        if test is None:
            return [
                f"x = {self.function(e)}(env)",
                "if x is False:",
                "    return False",
                "if x is not True:",
                "    out.append(x)",
            ]
        if self.grounder.static.get(e.pred) is not None:
            return [test[0].replace("x = ", "if not (", 1) + "):", "    return False"]
        return [test[0], "if b is None:", "    return False", "out.append(('lit', b, True))"]


def compile_formula(grounder, e, helpers: dict):
    """A function ``env -> residual`` equal to ``grounder.walk(e, env)``;
    ``helpers``: the residuals' ``conj``, ``disj`` and ``negate``."""
    src = _Source(grounder, helpers)
    top = src.function(e)
    ns = define(
        "\n".join(src.lines) + "\n", described("ground residual", getattr(e, "pos", None)), src.ns
    )
    return ns[top]


def _slots(args: tuple, const) -> str | None:
    """``(env[2], k7, )`` for arguments ``(?x, n0)`` (``const`` names a
    constant), or None when an argument is neither a variable nor a constant."""
    out = []
    for t in args:
        if type(t) is Var:
            out.append(f"env[{t.index}]")
        elif type(t) is str or type(t) is float:
            out.append(const(t))
        else:
            return None
    return "(" + "".join(x + ", " for x in out) + ")"


def compile_body(items: list, where=None):
    """A function ``env -> ((name, args), ...)`` of a method's subtasks, or
    None when an argument is neither a variable nor a constant."""
    ns: dict = {}

    def const(value) -> str:
        name = f"k{len(ns)}"
        ns[name] = value
        return name

    parts = []
    for x in items:
        args = _slots(x.args, const)
        if args is None:
            return None
        parts.append(f"({const(x.name)}, {args})")
    src = "def body(env):\n    return (" + "".join(p + ", " for p in parts) + ")\n"
    return define(src, described("ground method body", where), ns)["body"]
