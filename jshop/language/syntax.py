"""The parsed JSHOP2 language: domains, problems and their parts (manual 3.3-3.12).

Every element keeps ``pos``, a :class:`Pos` pointing at its source text, so that
any later error or warning can name ``file:line:col``.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from .record import FrozenRecord, Record
from .terms import CallTerm, Var


class Pos(FrozenRecord):
    __slots__ = ("file", "line", "col")
    file: str
    line: int
    col: int

    def __init__(self, file: str, line: int, col: int) -> None:
        object.__setattr__(self, "file", file)
        object.__setattr__(self, "line", line)
        object.__setattr__(self, "col", col)

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


# ------------------------------------------------------ logical expressions


class Atom(Record):
    """A logical atom ``(p t1 .. tn)`` (3.3); ``args`` is a tuple of terms."""

    __slots__ = ("pred", "args", "pos")

    def __init__(self, pred: str, args: tuple[Any, ...], pos: Pos | None = None) -> None:
        self.pred, self.args, self.pos = pred, args, pos


class VarAtom(Record):
    """A variable standing for an atom, bound at planning time (3.14)."""

    __slots__ = ("var", "pos")

    def __init__(self, var: Var, pos: Pos | None = None) -> None:
        self.var, self.pos = var, pos


class And(Record):
    __slots__ = ("items", "pos")

    def __init__(self, items: list[Any], pos: Pos | None = None) -> None:
        self.items, self.pos = items, pos


class Or(Record):
    __slots__ = ("items", "pos")

    def __init__(self, items: list[Any], pos: Pos | None = None) -> None:
        self.items, self.pos = items, pos


class Not(Record):
    __slots__ = ("expr", "pos")

    def __init__(self, expr: Any, pos: Pos | None = None) -> None:
        self.expr, self.pos = expr, pos


class ForAll(Record):
    """``(forall V Y Z)``: every satisfier of Y must satisfy Z (3.4.5)."""

    __slots__ = ("vars", "cond", "then", "pos")

    def __init__(self, vars: list[Var], cond: Any, then: Any, pos: Pos | None = None) -> None:
        self.vars, self.cond, self.then, self.pos = vars, cond, then, pos


class Equal(Record):
    """``(= t1 t2)`` (HDDL/PDDL equality): true when both sides are the same
    term; a side that is an unbound variable is bound to the other side."""

    __slots__ = ("left", "right", "pos")

    def __init__(self, left: Any, right: Any, pos: Pos | None = None) -> None:
        self.left, self.right, self.pos = left, right, pos


class Assign(Record):
    __slots__ = ("var", "term", "pos")

    def __init__(self, var: Var, term: Any, pos: Pos | None = None) -> None:
        self.var, self.term, self.pos = var, term, pos


class CallExpr(Record):
    """A call expression: true unless the call returns NIL (3.4.7)."""

    __slots__ = ("call", "pos")

    def __init__(self, call: CallTerm, pos: Pos | None = None) -> None:
        self.call, self.pos = call, pos


class Precondition(Record):
    """A logical precondition (3.5): plain, ``:first`` or ``:sort-by``.
    ``pulled``: the conjuncts of ``expr`` (the objects themselves) that the
    HDDL reader pulled up from the method's subtasks
    (:mod:`htn.jshop.readers.pullup`); not a field (neither shown nor compared)."""

    __slots__ = ("expr", "first", "sort_var", "comparator", "pos", "pulled")
    _fields = ("expr", "first", "sort_var", "comparator", "pos")

    def __init__(
        self,
        expr: Any,
        first: bool = False,
        sort_var: Var | None = None,
        comparator: str | None = None,
        pos: Pos | None = None,
        pulled: tuple[Any, ...] = (),
    ) -> None:
        self.expr, self.first, self.sort_var = expr, first, sort_var
        self.comparator = comparator  # '<', '>' or a user function name
        self.pos = pos
        self.pulled = pulled


# ------------------------------------------------------ operator effects


class Protection(Record):
    __slots__ = ("atom", "pos")

    def __init__(self, atom: Any, pos: Pos | None = None) -> None:
        self.atom = atom  # Atom or VarAtom
        self.pos = pos


class EffectForAll(Record):
    """``(forall V Y (a1 .. an))`` in a delete or add list (3.9)."""

    __slots__ = ("vars", "cond", "atoms", "pos")

    def __init__(
        self, vars: list[Var], cond: Any, atoms: list[Any], pos: Pos | None = None
    ) -> None:
        self.vars, self.cond = vars, cond
        self.atoms = atoms  # Atom or VarAtom
        self.pos = pos


class Effects(Record):
    """A delete or add list: a list of elements, or one variable (3.14)."""

    __slots__ = ("items", "var")

    def __init__(self, items: list[Any] | None = None, var: Var | None = None) -> None:
        self.items = list() if items is None else items
        self.var = var


# ------------------------------------------------------ tasks


class TaskAtom(Record):
    __slots__ = ("name", "args", "immediate", "pos")

    def __init__(
        self, name: str, args: tuple[Any, ...], immediate: bool = False, pos: Pos | None = None
    ) -> None:
        self.name, self.args, self.immediate, self.pos = name, args, immediate, pos

    @property
    def primitive(self) -> bool:
        return self.name.startswith("!")


class PartialOrder(tuple[tuple[int, ...], ...]):
    """A partial order on the members of a task list (HDDL ``:ordering``):
    entry ``i`` is the tuple of the indices of the members that must be
    finished before member ``i`` may start (its direct predecessors, each
    smaller than ``i``: members are kept in a topological order).

    It is falsy, like the ``ordered`` flag of an unordered list, so that
    every test "is this list totally ordered?" stays a truth test; JSHOP2's
    ``:unordered`` is the partial order with no pair ordered."""

    __slots__ = ()

    def __bool__(self) -> bool:
        return False

    def __repr__(self) -> str:
        return f"PartialOrder({tuple(self)!r})"


class TaskList(Record):
    """A task list (3.8): ``items`` are TaskAtoms and nested TaskLists.

    ``ordered`` lists run in order, others interleave (``:unordered``);
    ``order``, set by the HDDL reader only, is the partial order of an
    unordered list's members (None: no two members are ordered)."""

    __slots__ = ("items", "ordered", "pos", "order")

    def __init__(
        self,
        items: list[TaskAtom | TaskList],
        ordered: bool = True,
        pos: Pos | None = None,
        order: PartialOrder | None = None,
    ) -> None:
        self.items, self.ordered, self.pos, self.order = items, ordered, pos, order

    @property
    def order_flag(self) -> bool | PartialOrder:
        """What the search keeps for this list: True (in order), False
        (interleaved) or its :class:`PartialOrder`."""
        return self.order if self.order is not None else self.ordered


def task_atoms(tl: TaskList | TaskAtom) -> Iterator[TaskAtom]:
    """The task atoms of a task list (or a single atom), nested lists included."""
    if isinstance(tl, TaskAtom):
        yield tl
        return
    for x in tl.items:
        yield from task_atoms(x)


# ------------------------------------------------------ domain elements


class Operator(Record):
    __slots__ = ("head", "pre", "delete", "add", "cost", "nvars", "pos", "effects_in_prestate")

    # PDDL/HDDL semantics: every effect condition (forall, when) is evaluated
    # in the state before the operator, then deletions, then additions. JSHOP2
    # evaluates a delete list's forall while earlier atoms are already deleted
    # and the add list after all deletions (manual 5.2.1).

    def __init__(
        self,
        head: TaskAtom,
        pre: Precondition,
        delete: Effects,
        add: Effects,
        cost: Any,
        nvars: int = 0,
        pos: Pos | None = None,
        effects_in_prestate: bool = False,
    ) -> None:
        self.head, self.pre, self.delete, self.add = head, pre, delete, add
        self.cost = cost  # a term; default 1.0
        self.nvars, self.pos, self.effects_in_prestate = nvars, pos, effects_in_prestate

    @property
    def name(self) -> str:
        return self.head.name

    @property
    def internal(self) -> bool:
        return self.head.name.startswith("!!")


class Branch(Record):
    __slots__ = ("label", "pre", "tasks", "pos")

    def __init__(
        self, label: str, pre: Precondition, tasks: TaskList, pos: Pos | None = None
    ) -> None:
        self.label, self.pre, self.tasks, self.pos = label, pre, tasks, pos


class Method(Record):
    __slots__ = ("head", "branches", "nvars", "index", "pos")

    def __init__(
        self,
        head: TaskAtom,
        branches: list[Branch],
        nvars: int = 0,
        index: int = 0,
        pos: Pos | None = None,
    ) -> None:
        self.head, self.branches, self.nvars, self.index = head, branches, nvars, index
        self.pos = pos

    @property
    def name(self) -> str:
        return self.head.name


class AxiomBranch(Record):
    __slots__ = ("label", "pre", "pos")

    def __init__(self, label: str, pre: Precondition, pos: Pos | None = None) -> None:
        self.label, self.pre, self.pos = label, pre, pos


class Axiom(Record):
    __slots__ = ("head", "branches", "nvars", "pos")

    def __init__(
        self, head: Atom, branches: list[AxiomBranch], nvars: int = 0, pos: Pos | None = None
    ) -> None:
        self.head, self.branches, self.nvars, self.pos = head, branches, nvars, pos


class Domain(Record):
    __slots__ = (
        "name",
        "operators",
        "methods",
        "axioms",
        "file",
        "pos",
        "language",
        "facts",
        "implied",
        "spelling",
        "hddl",
        "pullup",
        "sha256",
    )

    # HDDL typing (empty for JSHOP2): ground atoms true in every problem (the
    # domain's constants and their types), and for a type predicate the
    # predicates of its supertypes ((truck t) also means (vehicle t)).

    def __init__(
        self,
        name: str,
        operators: dict[str, list[Operator]] | None = None,
        methods: dict[str, list[Method]] | None = None,
        axioms: dict[str, list[Axiom]] | None = None,
        file: str = "",
        pos: Pos | None = None,
        language: str = "jshop2",
        facts: list[Atom] | None = None,
        implied: dict[str, list[str]] | None = None,
        spelling: dict[str, str] | None = None,
        hddl: Any = None,
        pullup: bool = False,
        sha256: str = "",
    ) -> None:
        self.name = name
        self.operators = dict() if operators is None else operators  # name -> [Operator]
        self.methods = dict() if methods is None else methods  # name -> [Method]
        self.axioms = dict() if axioms is None else axioms  # pred -> [Axiom]
        self.file, self.pos, self.language = file, pos, language
        self.facts = list() if facts is None else facts
        self.implied = dict() if implied is None else implied  # pred -> [pred]
        self.spelling = dict() if spelling is None else spelling  # lower-case name -> as written
        self.hddl = hddl  # the HDDL model it was read from
        self.pullup = pullup  # HDDL: methods test pulled-up conditions
        self.sha256 = sha256

    def elements(self) -> Iterator[Operator | Method | Axiom]:
        for ops in self.operators.values():
            yield from ops
        for ms in self.methods.values():
            yield from ms
        for axs in self.axioms.values():
            yield from axs

    def dynamic_predicates(self) -> set[str]:
        """Predicates some operator adds or deletes: what execution can change."""
        preds: set[str] = set()
        for ops in self.operators.values():
            for op in ops:
                for eff in (op.delete, op.add):
                    for item in eff.items:
                        atoms = (
                            item.atoms
                            if isinstance(item, EffectForAll)
                            else [item.atom if isinstance(item, Protection) else item]
                        )
                        preds.update(a.pred for a in atoms if isinstance(a, Atom))
        return preds

    @property
    def n_methods(self) -> int:
        return sum(len(v) for v in self.methods.values())

    @property
    def n_operators(self) -> int:
        return sum(len(v) for v in self.operators.values())


class ProblemInstance(Record):
    """One state/task-list pair of a ``defproblem`` (3.12); an HDDL problem
    also has a goal, which a plan's final state must satisfy."""

    __slots__ = ("state", "tasks", "pos", "goal", "goal_nvars", "top", "root")

    # an HDDL initial task network with parameters: the (HDDL) method of an
    # artificial root task whose body is ``tasks`` and which binds them
    # ... and that method in the domain's terms (a Method, pulled-up
    # conditions included), built once the domain is known
    # (htn.jshop.readers.load.paired): what the searches and checks use

    def __init__(
        self,
        state: list[Atom],
        tasks: TaskList,
        pos: Pos | None = None,
        goal: Precondition | None = None,
        goal_nvars: int = 0,
        top: Any = None,
        root: Method | None = None,
    ) -> None:
        self.state = state  # ground
        self.tasks, self.pos, self.goal, self.goal_nvars = tasks, pos, goal, goal_nvars
        self.top, self.root = top, root


class Problem(Record):
    __slots__ = (
        "name",
        "domain_name",
        "instances",
        "file",
        "pos",
        "domain_pos",
        "language",
        "spelling",
        "hddl",
        "sha256",
    )

    def __init__(
        self,
        name: str,
        domain_name: str,
        instances: list[ProblemInstance],
        file: str = "",
        pos: Pos | None = None,
        domain_pos: Pos | None = None,
        language: str = "jshop2",
        spelling: dict[str, str] | None = None,
        hddl: Any = None,
        sha256: str = "",
    ) -> None:
        self.name, self.domain_name, self.instances, self.file = name, domain_name, instances, file
        self.pos = pos
        self.domain_pos = domain_pos  # where the domain's name is written
        self.language = language
        self.spelling = dict() if spelling is None else spelling  # lower-case name -> as written
        self.hddl = hddl  # the HDDL model it was read from
        self.sha256 = sha256


def root_method(instance: ProblemInstance) -> Method:
    """The root method of an HDDL instance whose initial task network has
    parameters (``instance.top``), as the reader built it with the domain."""
    if instance.root is None:
        raise ValueError(
            "an HDDL problem whose initial task network has parameters is "
            "planned once it is paired with its domain "
            "(htn.jshop.readers.load.paired, or htn.api's readers)"
        )
    return instance.root
