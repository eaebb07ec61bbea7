"""The HDDL model as read (Höller et al., AAAI 2020): tasks, methods, actions,
their task networks, and problems, before they are turned into the planner's
syntax objects (:mod:`htn.jshop.readers.hddl_domain`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from htn.jshop.language import syntax as S

# An initial task network with parameters is the body of this task's one
# method, which binds them (the IPC 2020 plan format's artificial root)
TOP, TOP_METHOD = "__top", "__top_method"


@dataclass
class Param:
    """A typed variable or object; ``types`` has several names for ``either``."""

    name: str
    types: tuple
    pos: S.Pos | None = None
    type_pos: S.Pos | None = None  # where its type is written


@dataclass
class TaskDef:
    name: str
    params: list
    pos: S.Pos | None = None


@dataclass
class Subtask:
    label: str | None
    name: str
    args: tuple
    pos: S.Pos | None = None


@dataclass
class Network:
    """A task network: subtasks, ``<`` constraints between labels, and
    whether it was written ``:ordered-subtasks``."""

    subtasks: list = field(default_factory=list)
    ordered: bool = False
    ordering: list = field(default_factory=list)  # [(before, after, pos)]
    constraints: object = None
    pos: S.Pos | None = None


@dataclass
class MethodDef:
    name: str
    params: list
    task: Subtask
    pre: object  # a syntax expression or None
    network: Network
    pos: S.Pos | None = None


@dataclass
class ActionDef:
    name: str
    params: list
    pre: object
    effect: object  # a nested effect structure, see Effect*
    pos: S.Pos | None = None


@dataclass
class Exists:
    """``(exists (typed vars) formula)``; becomes a conjunction with type
    conditions when translated (its variables renamed apart)."""

    vars: list
    expr: object
    pos: S.Pos | None = None


@dataclass
class EffectWhen:
    vars: list  # [Param] of enclosing foralls
    cond: object
    effect: object
    pos: S.Pos | None = None


@dataclass
class EffectForall:
    vars: list
    effect: object
    pos: S.Pos | None = None


@dataclass
class EffectCost:
    amount: object  # a number
    pos: S.Pos | None = None


@dataclass
class HDomain:
    name: str
    types: dict = field(default_factory=dict)  # type -> [parent types]
    type_pos: dict = field(default_factory=dict)  # type -> where it is first declared
    constants: list = field(default_factory=list)  # [Param]
    predicates: dict = field(default_factory=dict)  # name -> [Param]
    tasks: dict = field(default_factory=dict)  # name -> TaskDef
    methods: list = field(default_factory=list)
    actions: dict = field(default_factory=dict)  # name -> ActionDef
    spelling: dict = field(default_factory=dict)
    file: str = ""
    pos: S.Pos | None = None


@dataclass
class HProblem:
    name: str
    domain_name: str
    objects: list = field(default_factory=list)
    params: list = field(default_factory=list)
    network: Network | None = None
    init: list = field(default_factory=list)  # [S.Atom]
    goal: object = None
    spelling: dict = field(default_factory=dict)
    file: str = ""
    pos: S.Pos | None = None


# ------------------------------------------------------------------ builder
