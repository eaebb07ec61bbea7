"""The evaluation of plan transformations (the plan-transformations paper,
Section IV-A): a plan and its transformed version executed many times
(:mod:`.study`, :mod:`.runs`), on this process or a Dask cluster
(:mod:`.cluster`), compared (:mod:`.statistics`) and plotted
(:mod:`.figures`)."""
