"""Plans and what is made of them: plans (:mod:`.plan`), task trees
(:mod:`.tree`), plan files (:mod:`.planfile`), the IPC plan format
(:mod:`.ipc`), validation (:mod:`.validate`), and why there is no plan
(:mod:`.explain`, :mod:`.unsatisfied`)."""
