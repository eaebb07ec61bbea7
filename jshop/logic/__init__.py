"""The logic engine: satisfiers of preconditions in a state (:mod:`.engine`),
the world state (:mod:`.state`), operators applied to it (:mod:`.operators`),
and the code generated for speed (:mod:`.compile`: terms, heads and task
lists; :mod:`.modes`: conjunctions per binding mode; :mod:`.caches`)."""
