"""The browser view of a run: ``htn run PLAN --view`` (live) and ``htn view
run.jsonl`` (a finished log, with a scrubber).

* :mod:`htn.view.model` - the page's input: the events of a log, read and
  checked, with the task tree they need (``tree`` events,
  :mod:`htn.executor.tree_events`);
* :mod:`htn.view.hub` - between the robot's thread and the pages: every
  event and the latest camera frame, handed over without ever blocking a tick;
* :mod:`htn.view.server` - the local web server (Starlette on uvicorn, the
  ``view`` extra) with its per-run token;
* :mod:`htn.view.live` - attaching the view to a run: the log's listener and
  the camera, rendered between ticks at a bounded rate;
* ``static/`` - the page (HTML, CSS, plain JavaScript), shipped inside the
  package: it loads nothing from the network.
"""
