"""Robot interface and its worlds: PyBullet simulations (the domestic robot,
the two-armed kitchen robot) and the fast projection."""


def simulated_robot(state, gui: bool = False, faults=None, seed: int = 0):
    """The PyBullet robot for a problem's initial state: the kitchen robot for
    the kitchen vocabulary (``(area ...)`` facts), else the domestic one."""
    from .world import is_kitchen_state, kitchen_world_from_state, world_from_state

    if is_kitchen_state(state):
        from .kitchen_sim import KitchenRobot

        return KitchenRobot(kitchen_world_from_state(state), gui=gui, faults=faults, seed=seed)
    from .pybullet_sim import PyBulletRobot

    return PyBulletRobot(world_from_state(state), gui=gui, faults=faults, seed=seed)
