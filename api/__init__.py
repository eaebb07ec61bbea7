"""The use cases of htn, one function each: the public API that the command
line calls (it only parses arguments and prints).

* :func:`htn.api.plan.plan` - the plans of a problem, with task trees and statistics;
* :func:`htn.api.run.run` - execute a plan on a robot with monitoring (and
  :func:`htn.api.run.prepare` to act before its first tick);
* :func:`htn.api.validate.validate` - replay plans from the initial state;
* :func:`htn.api.transform.transform` - transform a plan's task tree;
* :func:`htn.api.evaluate.evaluate` - compare a plan with its transformed plan over many runs;
* :func:`htn.api.stats.stats` - the planning paper's Table 1 for scenarios.

Each is also ``htn.<name>`` (imported on first use). Inputs are paths or
loaded objects (:mod:`.inputs`); files written are checked first and replaced
whole (:mod:`.files`). Errors in the input are
:class:`htn.jshop.language.errors.HtnError`, located at ``file:line:col``;
nothing here prints, exits or installs signal handlers.
"""
