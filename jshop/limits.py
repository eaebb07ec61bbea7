"""Limits of the search that the command line shows as defaults.

Kept apart from :mod:`htn.jshop.planner` so that ``htn --help`` can show them
without loading the planner.
"""

# The search depth is the number of nested ``findPlanHelper`` calls (frames on
# the planner's stack: one per reduction and per operator applied on the
# current path). No plan of the JSHOP2 corpus or of the IPC 2020 sample comes
# near this bound (a tail recursion takes about three frames per step: Towers
# with 16 rings, 65,535 moves, about 200,000); a method that decomposes into
# itself without end reaches it in a few seconds and well under 1 GB of memory
# (about 1.7 kB per frame).
DEFAULT_MAX_DEPTH = 250_000
