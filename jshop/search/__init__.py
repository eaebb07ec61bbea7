"""The search for plans: JSHOP2's depth-first decomposition (:mod:`.planner`),
its bounds (:mod:`.limits`), and what it adds for HDDL domains: the loop
check (:mod:`.loops`) and the goal guard (:mod:`.goals`)."""
