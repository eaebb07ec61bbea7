"""Task dispatcher, action state machines as behaviour trees, repair, event log.

Nothing here is imported by ``jshop``.
"""
