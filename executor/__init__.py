"""Task dispatcher and action state machines (execution with monitoring).

Not implemented yet: see the executor issue. Nothing here is imported by
``jshop``.
"""
