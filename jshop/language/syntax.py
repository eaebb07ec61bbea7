"""The parsed JSHOP2 language: domains, problems and their parts (manual 3.3-3.12).

Every element keeps ``pos``, a :class:`Pos` pointing at its source text, so that
any later error or warning can name ``file:line:col``.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from .terms import CallTerm, Var


@dataclass(frozen=True)
class Pos:
    file: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


# ------------------------------------------------------ logical expressions


@dataclass
class Atom:
    """A logical atom ``(p t1 .. tn)`` (3.3); ``args`` is a tuple of terms."""

    pred: str
    args: tuple[Any, ...]
    pos: Pos | None = None


@dataclass
class VarAtom:
    """A variable standing for an atom, bound at planning time (3.14)."""

    var: Var
    pos: Pos | None = None


@dataclass
class And:
    items: list[Any]
    pos: Pos | None = None


@dataclass
class Or:
    items: list[Any]
    pos: Pos | None = None


@dataclass
class Not:
    expr: Any
    pos: Pos | None = None


@dataclass
class ForAll:
    """``(forall V Y Z)``: every satisfier of Y must satisfy Z (3.4.5)."""

    vars: list[Var]
    cond: Any
    then: Any
    pos: Pos | None = None


@dataclass
class Equal:
    """``(= t1 t2)`` (HDDL/PDDL equality): true when both sides are the same
    term; a side that is an unbound variable is bound to the other side."""

    left: Any
    right: Any
    pos: Pos | None = None


@dataclass
class Assign:
    var: Var
    term: Any
    pos: Pos | None = None


@dataclass
class CallExpr:
    """A call expression: true unless the call returns NIL (3.4.7)."""

    call: CallTerm
    pos: Pos | None = None


@dataclass
class Precondition:
    """A logical precondition (3.5): plain, ``:first`` or ``:sort-by``."""

    expr: Any
    first: bool = False
    sort_var: Var | None = None
    comparator: str | None = None  # '<', '>' or a user function name
    pos: Pos | None = None


# ------------------------------------------------------ operator effects


@dataclass
class Protection:
    atom: Any  # Atom or VarAtom
    pos: Pos | None = None


@dataclass
class EffectForAll:
    """``(forall V Y (a1 .. an))`` in a delete or add list (3.9)."""

    vars: list[Var]
    cond: Any
    atoms: list[Any]  # Atom or VarAtom
    pos: Pos | None = None


@dataclass
class Effects:
    """A delete or add list: a list of elements, or one variable (3.14)."""

    items: list[Any] = field(default_factory=list)
    var: Var | None = None


# ------------------------------------------------------ tasks


@dataclass
class TaskAtom:
    name: str
    args: tuple[Any, ...]
    immediate: bool = False
    pos: Pos | None = None

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


@dataclass
class TaskList:
    """A task list (3.8): ``items`` are TaskAtoms and nested TaskLists.

    ``ordered`` lists run in order, others interleave (``:unordered``);
    ``order``, set by the HDDL reader only, is the partial order of an
    unordered list's members (None: no two members are ordered)."""

    items: list[TaskAtom | TaskList]
    ordered: bool = True
    pos: Pos | None = None
    order: PartialOrder | None = None

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


@dataclass
class Operator:
    head: TaskAtom
    pre: Precondition
    delete: Effects
    add: Effects
    cost: Any  # a term; default 1.0
    nvars: int = 0
    pos: Pos | None = None
    # PDDL/HDDL semantics: every effect condition (forall, when) is evaluated
    # in the state before the operator, then deletions, then additions. JSHOP2
    # evaluates a delete list's forall while earlier atoms are already deleted
    # and the add list after all deletions (manual 5.2.1).
    effects_in_prestate: bool = False

    @property
    def name(self) -> str:
        return self.head.name

    @property
    def internal(self) -> bool:
        return self.head.name.startswith("!!")


@dataclass
class Branch:
    label: str
    pre: Precondition
    tasks: TaskList
    pos: Pos | None = None


@dataclass
class Method:
    head: TaskAtom
    branches: list[Branch]
    nvars: int = 0
    index: int = 0
    pos: Pos | None = None

    @property
    def name(self) -> str:
        return self.head.name


@dataclass
class AxiomBranch:
    label: str
    pre: Precondition
    pos: Pos | None = None


@dataclass
class Axiom:
    head: Atom
    branches: list[AxiomBranch]
    nvars: int = 0
    pos: Pos | None = None


@dataclass
class Domain:
    name: str
    operators: dict[str, list[Operator]] = field(default_factory=dict)  # name -> [Operator]
    methods: dict[str, list[Method]] = field(default_factory=dict)  # name -> [Method]
    axioms: dict[str, list[Axiom]] = field(default_factory=dict)  # pred -> [Axiom]
    file: str = ""
    pos: Pos | None = None
    language: str = "jshop2"  # or "hddl": the file it was read from
    # HDDL typing (empty for JSHOP2): ground atoms true in every problem (the
    # domain's constants and their types), and for a type predicate the
    # predicates of its supertypes ((truck t) also means (vehicle t)).
    facts: list[Atom] = field(default_factory=list)
    implied: dict[str, list[str]] = field(default_factory=dict)  # pred -> [pred]
    spelling: dict[str, str] = field(default_factory=dict)  # lower-case name -> as written
    hddl: Any = None  # the HDDL model it was read from
    pullup: bool = False  # HDDL: methods test pulled-up conditions
    sha256: str = ""  # of the bytes it was parsed from

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


@dataclass
class ProblemInstance:
    """One state/task-list pair of a ``defproblem`` (3.12); an HDDL problem
    also has a goal, which a plan's final state must satisfy."""

    state: list[Atom]  # ground
    tasks: TaskList
    pos: Pos | None = None
    goal: Precondition | None = None
    goal_nvars: int = 0
    # an HDDL initial task network with parameters: the (HDDL) method of an
    # artificial root task whose body is ``tasks`` and which binds them
    top: Any = None
    # ... and that method in the domain's terms (a Method, pulled-up
    # conditions included), built once the domain is known
    # (htn.jshop.readers.load.paired): what the searches and checks use
    root: Method | None = None


@dataclass
class Problem:
    name: str
    domain_name: str
    instances: list[ProblemInstance]
    file: str = ""
    pos: Pos | None = None
    domain_pos: Pos | None = None  # where the domain's name is written
    language: str = "jshop2"
    spelling: dict[str, str] = field(default_factory=dict)  # lower-case name -> as written
    hddl: Any = None  # the HDDL model it was read from
    sha256: str = ""  # of the bytes it was parsed from


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
