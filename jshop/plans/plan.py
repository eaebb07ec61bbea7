"""Plans: sequences of ground operator instances with a cost (manual 3.13)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from htn.jshop.language.record import Record
from htn.jshop.language.terms import atom_str, java_double

if TYPE_CHECKING:
    from .tree import TaskTree

SEPARATOR = "--------------------"


class Step(Record):
    """One operator instance in a plan; ``internal`` for ``!!`` operators."""

    __slots__ = ("name", "args", "cost", "line")

    def __init__(self, name: str, args: tuple[Any, ...], cost: float = 1.0, line: int = 0) -> None:
        self.name, self.args, self.cost = name, args, cost
        self.line = line  # line in a plan file it was read from (0: not read)

    @property
    def internal(self) -> bool:
        return self.name.startswith("!!")

    def __str__(self) -> str:
        return atom_str(self.name, self.args)


class Plan(Record):
    """A plan: its steps and their cost. ``instance``, set by the search's
    stream, is the problem instance's index (not a field: not compared)."""

    __slots__ = ("steps", "cost", "tree", "index", "line", "instance")
    _fields = ("steps", "cost", "tree", "index", "line")

    def __init__(
        self,
        steps: list[Step],
        cost: float,
        tree: TaskTree | None = None,
        index: int = 0,
        line: int = 0,
    ) -> None:
        self.steps, self.cost = steps, cost
        self.tree = tree  # when recorded
        self.index = index  # 0-based position in the planner's stream
        self.line = line  # line of its 'Plan cost:' in a plan file it was read from
        self.instance = 0

    def __len__(self) -> int:
        return len(self.steps)

    def lines(self) -> list[str]:
        return [str(s) for s in self.steps]

    def to_jshop(self) -> str:
        """Exactly JSHOP2's ``Plan.toString()``."""
        body = "".join(line + "\n" for line in self.lines())
        return f"Plan cost: {java_double(self.cost)}\n\n{body}{SEPARATOR}\n"
