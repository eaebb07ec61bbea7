"""Action state machines: the life cycle every operator runs (:mod:`.base`)
and the machines of the bundled domains (:mod:`.domestic`: the RoboCup@Home
robot; :mod:`.kitchen`: the two-armed pick-and-place robot).

A plugin registers its own with ``@htn.executor.machines.action("!op")``, and
says which predicate names what the robot carries with
``htn.executor.machines.carried_by("holding", domain=...)``.
"""

from .base import ActionMachine, HoldMonitor, action, all_of, carried_by, machine_for

__all__ = ["ActionMachine", "HoldMonitor", "action", "all_of", "carried_by", "machine_for"]
