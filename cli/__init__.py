"""The ``htn`` command line: parses arguments and prints; no planning logic."""
