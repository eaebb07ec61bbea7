"""Goal reachability below the network: cut a search node whose goal the
actions its network can still bring in cannot make true (for the heuristic
search over a grounded problem).

In progression search every action a plan below a node adds comes from
refining a task left in the node's network. So if the problem's goal fails
in the delete relaxation from the node's state *with only those actions*,
the node is a dead end. This is the restriction that Höller, Bercher,
Behnke and Biundo make in their RC heuristic's second form (the actions of
the relaxed model need a "reachable" fact that only tasks of the current
network give; JAIR 2020, "HTN Planning as Heuristic Progression Search";
PANDA's ``rc2``), used here as a test, beside RC-add
(:mod:`.heuristics`), which lets every action of the domain take part.

IPC 2020's Woodworking shows why it matters: a plan may glaze part p5 where
the goal wants it varnished. Varnishing it again needs it untreated, which
only grinding it does, and only a task that processes p5 brings in its
grinding; once that task is done, the goal is lost. RC-add still sees it
reachable, and GBFS on instance 09 made 260k expansions in 40 s without a
plan; with this cut it finds one after 98.

The test goes two levels deep, which is cheap enough for every node. Per
task, the *relevant* facts (the goal's, and the positive preconditions of
the actions adding a goal fact) that some action below it adds are a mask,
computed once bottom up over the task decomposition graph; a node's mask
is the union over its network. A goal fact missing from the state must be
in it, and one of the actions adding the fact must have each positive
precondition true in the state or in the mask. Deletes, negative and other
conditions, and method preconditions are ignored, so no plan is lost.

(A first version kept, per task, the relevant actions below it and ran the
relaxed fixpoint over them: 84 expansions on Woodworking 09 instead of 98,
but Multiarm-Blocksworld pfile_02_055 took 20.6 s for the 2,052 expansions
that take 2.0 s without a cut, and the masks of Woodworking 18's 39k tasks
over 13k actions were too large to keep. Masks of facts take 0.09 s to
build there, and Multiarm's search is as fast as without the cut.)
"""

from __future__ import annotations

from .ground_formulas import bits
from .task_networks import tasks

MAX_BITS = 200_000_000  # relevant facts x tasks with a mask, at most: else off


class GoalReach:
    """``ok(state, network)``: False where the goal cannot be reached with
    the actions below the network (see the module docstring)."""

    def __init__(self, model):
        goal = model.goal[0] if model.goal is not None else 0
        self.goal = goal
        self.active = False
        if goal <= 0:
            return
        adds_of = {t: a.possible_adds() for t, a in model.actions.items()}
        # per goal fact, the positive preconditions of the actions adding it
        self.pres: dict = {g: [] for g in bits(goal)}
        relevant = goal  # the goal's facts and their adders' preconditions
        for t, adds in adds_of.items():
            if adds & goal:
                pre = model.actions[t].pre[0]
                relevant |= pre
                for g in bits(adds & goal):
                    self.pres[g].append(pre)
        below = _below(model, adds_of, relevant, MAX_BITS)
        if below is None:
            return
        self.below = below
        self.active = True

    def ok(self, state: int, net: tuple) -> bool:
        missing = self.goal & ~state
        if not missing or not self.active:
            return True
        below, can = self.below, 0
        for t in tasks(net):
            can |= below.get(t, 0)
        if missing & ~can:
            return False  # a goal fact no action below the network adds
        pres = self.pres
        for g in bits(missing):
            for pre in pres[g]:
                if not pre & ~state & ~can:
                    break  # each precondition holds or is added below
            else:
                return False
        return True


def _below(model, adds_of: dict, relevant: int, max_bits: int):
    """Per task, the relevant facts that actions below it add (for an
    action, its own), for the tasks with any; None where the masks would
    hold more than ``max_bits`` bits in all."""
    users = model.parents()
    below = {t: adds & relevant for t, adds in adds_of.items() if adds & relevant}
    work = list(below)
    budget = max_bits // max(1, relevant.bit_count())  # tasks with a mask, at most
    budget -= len(below)
    while work:
        t = work.pop()
        m = below[t]
        for u in users.get(t, ()):
            old = below.get(u, 0)
            if m | old != old:
                if not old:
                    budget -= 1
                    if budget < 0:
                        return None
                below[u] = m | old
                work.append(u)
    return below
