"""Plans and what is made of them, as data: plans (:mod:`.plan`), task
trees (:mod:`.tree`, :mod:`.tree_text`), plan files (:mod:`.planfile`) and
the IPC plan format (:mod:`.ipc`). What checks them by running the search
is in :mod:`htn.jshop.checks`."""
