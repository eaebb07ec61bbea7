"""Plans: sequences of ground operator instances with a cost (manual 3.13)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from htn.jshop.language.terms import atom_str, java_double

if TYPE_CHECKING:
    from .tree import TaskTree

SEPARATOR = "--------------------"


@dataclass
class Step:
    """One operator instance in a plan; ``internal`` for ``!!`` operators."""

    name: str
    args: tuple[Any, ...]
    cost: float = 1.0
    line: int = 0  # line in a plan file it was read from (0: not read)

    @property
    def internal(self) -> bool:
        return self.name.startswith("!!")

    def __str__(self) -> str:
        return atom_str(self.name, self.args)


@dataclass
class Plan:
    steps: list[Step]
    cost: float
    tree: TaskTree | None = None  # when recorded
    index: int = 0  # 0-based position in the planner's stream
    line: int = 0  # line of its 'Plan cost:' in a plan file it was read from

    def __len__(self) -> int:
        return len(self.steps)

    def lines(self) -> list[str]:
        return [str(s) for s in self.steps]

    def to_jshop(self) -> str:
        """Exactly JSHOP2's ``Plan.toString()``."""
        body = "".join(line + "\n" for line in self.lines())
        return f"Plan cost: {java_double(self.cost)}\n\n{body}{SEPARATOR}\n"
