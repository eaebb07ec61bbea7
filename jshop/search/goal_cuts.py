"""The goal's cuts for the heuristic search, together: the goal-chain cut
(:mod:`.goal_chain`) where the goal has a chain, and the goal-reachability
cut (:mod:`.goal_reach`). A node is kept where each active cut keeps it;
the cheaper reachability test goes first."""

from __future__ import annotations

from typing import Protocol

from .goal_chain import GoalChain
from .goal_reach import GoalReach
from .grounding import UNREACHABLE_GOAL


class Cut(Protocol):
    def ok(self, state: int, net: tuple) -> bool: ...


class _Both:
    """Two cuts: a node is kept where each keeps it."""

    def __init__(self, first: Cut, second: Cut):
        self.first, self.second = first, second

    def ok(self, state: int, net: tuple) -> bool:
        return self.first.ok(state, net) and self.second.ok(state, net)


def goal_cuts(model) -> Cut | None:
    """The active cuts of ``model``'s goal, None where there are none."""
    if model.goal is None or model.goal == UNREACHABLE_GOAL:
        return None
    cuts = [c for c in (GoalReach(model), GoalChain(model)) if c.active]
    if len(cuts) == 2:
        return _Both(*cuts)
    return cuts[0] if cuts else None


def chained(cut: Cut | None) -> bool:
    """Whether the goal-chain cut is one of ``cut``'s (the portfolio's share
    for GBFS with TDG_m depends on it)."""
    return isinstance(cut, GoalChain) or (
        isinstance(cut, _Both) and isinstance(cut.second, GoalChain)
    )
