"""The use cases of htn, one function each: the public API that the command
line calls."""
