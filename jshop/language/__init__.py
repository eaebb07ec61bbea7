"""The JSHOP2 language that every part of the planner shares: terms and
unification (:mod:`.terms`), the syntax objects of domains and problems
(:mod:`.syntax`), walkers over their variables (:mod:`.walk`), the callable
functions (:mod:`.functions`) and the located errors (:mod:`.errors`)."""
