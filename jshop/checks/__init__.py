"""Checks that run the search or the logic over plans: validation
(:mod:`.validate`), why there is no plan (:mod:`.explain`,
:mod:`.unsatisfied`), the IPC plan verifier (:mod:`.ipc_verify` with
:mod:`.ipc_match` and :mod:`.ipc_replay`), and the recovery of a plan's
task tree by planning again (:mod:`.recover`). They stand above the search;
the plans themselves (:mod:`htn.jshop.plans`) are data below it."""
