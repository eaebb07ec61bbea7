"""The HDDL model as read (Höller et al., AAAI 2020): tasks, methods, actions,
their task networks, and problems, before they are turned into the planner's
syntax objects (:mod:`htn.jshop.readers.hddl_domain`).

Plain classes with ``__slots__`` rather than dataclasses
(:mod:`htn.jshop.language.record`: making these thirteen dataclasses cost 4
ms of CPU at import, for every HDDL input).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from htn.jshop.language.record import Record

if TYPE_CHECKING:
    from htn.jshop.language import syntax as S

# An initial task network with parameters is the body of this task's one
# method, which binds them (the IPC 2020 plan format's artificial root)
TOP, TOP_METHOD = "__top", "__top_method"


class Param(Record):
    """A typed variable or object; ``types`` has several names for ``either``."""

    __slots__ = ("name", "types", "pos", "type_pos")

    def __init__(
        self, name: str, types: tuple, pos: S.Pos | None = None, type_pos: S.Pos | None = None
    ):
        self.name, self.types, self.pos = name, types, pos
        self.type_pos = type_pos  # where its type is written


class TaskDef(Record):
    __slots__ = ("name", "params", "pos")

    def __init__(self, name: str, params: list, pos: S.Pos | None = None):
        self.name, self.params, self.pos = name, params, pos


class Subtask(Record):
    __slots__ = ("label", "name", "args", "pos")

    def __init__(self, label: str | None, name: str, args: tuple, pos: S.Pos | None = None):
        self.label, self.name, self.args, self.pos = label, name, args, pos


class Network(Record):
    """A task network: subtasks, ``<`` constraints between labels, and
    whether it was written ``:ordered-subtasks``."""

    __slots__ = ("subtasks", "ordered", "ordering", "constraints", "pos")

    def __init__(
        self,
        subtasks: list | None = None,
        ordered: bool = False,
        ordering: list | None = None,  # [(before, after, pos)]
        constraints: object = None,
        pos: S.Pos | None = None,
    ):
        self.subtasks = [] if subtasks is None else subtasks
        self.ordered = ordered
        self.ordering = [] if ordering is None else ordering
        self.constraints, self.pos = constraints, pos


class MethodDef(Record):
    __slots__ = ("name", "params", "task", "pre", "network", "pos")

    def __init__(
        self,
        name: str,
        params: list,
        task: Subtask,
        pre: object,  # a syntax expression or None
        network: Network,
        pos: S.Pos | None = None,
    ):
        self.name, self.params, self.task, self.pre = name, params, task, pre
        self.network, self.pos = network, pos


class ActionDef(Record):
    __slots__ = ("name", "params", "pre", "effect", "pos")

    def __init__(
        self,
        name: str,
        params: list,
        pre: object,
        effect: object,  # a nested effect structure, see Effect*
        pos: S.Pos | None = None,
    ):
        self.name, self.params, self.pre, self.effect, self.pos = name, params, pre, effect, pos


class Exists(Record):
    """``(exists (typed vars) formula)``; becomes a conjunction with type
    conditions when translated (its variables renamed apart)."""

    __slots__ = ("vars", "expr", "pos")

    def __init__(self, vars: list, expr: object, pos: S.Pos | None = None):
        self.vars, self.expr, self.pos = vars, expr, pos


class EffectWhen(Record):
    __slots__ = ("vars", "cond", "effect", "pos")

    def __init__(self, vars: list, cond: object, effect: object, pos: S.Pos | None = None):
        self.vars = vars  # [Param] of enclosing foralls
        self.cond, self.effect, self.pos = cond, effect, pos


class EffectForall(Record):
    __slots__ = ("vars", "effect", "pos")

    def __init__(self, vars: list, effect: object, pos: S.Pos | None = None):
        self.vars, self.effect, self.pos = vars, effect, pos


class EffectCost(Record):
    __slots__ = ("amount", "pos")

    def __init__(self, amount: object, pos: S.Pos | None = None):
        self.amount, self.pos = amount, pos  # a number


class HDomain(Record):
    __slots__ = (
        "name",
        "types",
        "type_pos",
        "constants",
        "predicates",
        "tasks",
        "methods",
        "actions",
        "spelling",
        "file",
        "pos",
    )

    def __init__(self, name: str, file: str = "", pos: S.Pos | None = None, **given: Any):
        self.name = name
        self.types: dict = given.pop("types", {})  # type -> [parent types]
        self.type_pos: dict = given.pop("type_pos", {})  # type -> where first declared
        self.constants: list = given.pop("constants", [])  # [Param]
        self.predicates: dict = given.pop("predicates", {})  # name -> [Param]
        self.tasks: dict = given.pop("tasks", {})  # name -> TaskDef
        self.methods: list = given.pop("methods", [])
        self.actions: dict = given.pop("actions", {})  # name -> ActionDef
        self.spelling: dict = given.pop("spelling", {})
        self.file, self.pos = file, pos
        if given:
            raise TypeError(f"HDomain() got unexpected fields {sorted(given)}")


class HProblem(Record):
    __slots__ = (
        "name",
        "domain_name",
        "objects",
        "params",
        "network",
        "init",
        "goal",
        "spelling",
        "file",
        "pos",
    )

    def __init__(
        self,
        name: str,
        domain_name: str,
        file: str = "",
        pos: S.Pos | None = None,
        **given: Any,
    ):
        self.name, self.domain_name = name, domain_name
        self.objects: list = given.pop("objects", [])
        self.params: list = given.pop("params", [])
        self.network: Network | None = given.pop("network", None)
        self.init: list = given.pop("init", [])  # [S.Atom]
        self.goal: object = given.pop("goal", None)
        self.spelling: dict = given.pop("spelling", {})
        self.file, self.pos = file, pos
        if given:
            raise TypeError(f"HProblem() got unexpected fields {sorted(given)}")
