"""Robot interface and its worlds (PyBullet simulation, fast projection).

Not implemented yet: see the executor and plan-transformation issues.
"""
