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

The test goes two levels deep, which is cheap enough for every node: each
goal fact missing from the state needs an action below the network that
adds it and whose positive preconditions each hold in the state or are
added by some action below the network. The *relevant* actions are those
adding a goal fact or a positive precondition of such an adder; per task,
a mask of the relevant actions below it (the task decomposition graph,
bottom up) is computed once, and a node's mask is the union over its
network. Deletes, negative and other conditions, and method preconditions
are ignored, so no plan is lost. (A first version ran the full relaxed
fixpoint over the masked actions: 84 expansions on Woodworking 09 instead
of 98, but Multiarm-Blocksworld pfile_02_055 took 20.6 s for the 2,052
expansions that take 2.0 s without a cut, and 2.3 s with this one.)
"""

from __future__ import annotations

from .task_networks import tasks

MAX_BITS = 60_000_000  # relevant actions x tasks with a mask, at most: else off


class GoalReach:
    """``ok(state, network)``: False where the goal cannot be reached with
    the actions below the network (see the module docstring)."""

    def __init__(self, model):
        goal = model.goal[0] if model.goal is not None else 0
        self.goal = goal
        self.active = False
        if goal <= 0:
            return
        adders: dict = {}  # fact -> ids of the actions adding it
        adds_of = {}
        for t, a in model.actions.items():
            adds = a.adds
            for _c, _d, more in a.effects:
                adds |= more
            adds_of[t] = adds
            for b in _bits(adds):
                adders.setdefault(b, []).append(t)
        relevant: dict = {}  # action id -> bit index
        facts = set(_bits(goal))
        for g in _bits(goal):  # the goal's adders, then their preconditions' adders
            for t in adders.get(g, ()):
                facts.update(_bits(model.actions[t].pre[0]))
        for f in facts:
            for t in adders.get(f, ()):
                relevant.setdefault(t, len(relevant))
        # the positive preconditions of each relevant action, by bit index
        self.acts = [model.actions[t].pre[0] for t in relevant]
        self.adders = {
            b: sum(1 << relevant[t] for t in ts) for b, ts in adders.items() if b in facts
        }
        below = _below(model, relevant, MAX_BITS)
        if below is None:
            return
        self.below = below
        self.active = bool(relevant)
        self.cuts = 0

    def ok(self, state: int, net: tuple) -> bool:
        goal = self.goal
        missing = goal & ~state
        if not missing or not self.active:
            return True
        below, mask = self.below, 0
        for t in tasks(net):
            mask |= below.get(t, 0)
        acts, adders = self.acts, self.adders
        for b in _bits(missing):
            can = adders.get(b, 0) & mask
            if not can:
                return False
            for i in _bits(can):
                need = acts[i] & ~state
                if not need or all(adders.get(p, 0) & mask for p in _bits(need)):
                    break
            else:
                return False
        return True


def _below(model, relevant: dict, max_bits: int):
    """Per task, the mask of the relevant actions below it (the task itself
    for an action), for the tasks with any; None where the masks would hold
    more than ``max_bits`` bits in all."""
    users: dict = {}
    for t, ms in model.methods_of.items():
        for gm in ms:
            for s in gm.body:
                users.setdefault(s, set()).add(t)
    below = {t: 1 << i for t, i in relevant.items()}
    work = list(below)
    budget = max_bits // max(1, len(relevant))  # tasks with a mask, at most
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


def _bits(mask: int) -> list:
    out = []
    while mask:
        low = mask & -mask
        out.append(low.bit_length() - 1)
        mask ^= low
    return out
