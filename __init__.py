"""htn: JSHOP2-compatible HTN planning, monitored plan execution on robots,
and plan transformations.

One import package. Its parts are the repository's top-level folders:

* :mod:`htn.jshop` - reads JSHOP2 and HDDL domains and problems, plans (no robot, no CLI);
* :mod:`htn.executor` - task dispatcher, action state machines, outcome log;
* :mod:`htn.robot` - robot back ends: PyBullet (``sim`` extra), projection, symbolic;
* :mod:`htn.transform` - plan transformations over task trees;
* :mod:`htn.evaluation` - their evaluation over many runs (``eval`` extra);
* :mod:`htn.view` - the browser view of a run or a log (``view`` extra);
* :mod:`htn.api` - the use cases, one function each (what the command line calls);
* :mod:`htn.cli` - the ``htn`` command line (also ``python -m htn``).

The use cases are callable from here (each imported on first use, so that
``import htn`` stays fast)::

    import htn
    plans = htn.plan("domains/domestic.jshop", "problems/bring_object.jshop", plans=3)
    for p in plans: ...                         # plans with their task trees
    result = htn.run(p, domain=plans.domain, problem=plans.problem, robot="symbolic")

:func:`plan`, :func:`run`, :func:`validate`, :func:`transform_plan`,
:func:`evaluate` and :func:`stats` (see :mod:`htn.api` for their
signatures). ``htn.transform`` is the package of the transformation
framework (``htn.transform.framework``).

The bundled example domains and problems are in :data:`EXAMPLES`; the
install extras and the modules each brings are in :data:`EXTRAS`.
"""

__all__ = [
    "EXAMPLES",
    "EXTRAS",
    "missing_modules",
    "plan",
    "run",
    "validate",
    "transform_plan",
    "evaluate",
    "stats",
]

# the use cases by name: the module of htn.api that holds each (imported on first use)
USE_CASES = {
    "plan": "htn.api.plan",
    "run": "htn.api.run",
    "validate": "htn.api.validate",
    "transform_plan": "htn.api.transform",
    "evaluate": "htn.api.evaluate",
    "stats": "htn.api.stats",
}


def _use_case(name: str):
    from importlib import import_module

    return getattr(import_module(USE_CASES[name]), name)


def __getattr__(name):
    if name in USE_CASES:
        value = _use_case(name)
        globals()[name] = value
        return value
    if name in ("EXAMPLES", "EXTRAS", "missing_modules"):  # pathlib only when asked for
        from . import installation

        return getattr(installation, name)
    # the version is read from the installed metadata only when asked for
    if name == "__version__":
        from .installation import version

        return version()
    raise AttributeError(f"module 'htn' has no attribute {name!r}")


def __dir__():
    return sorted({*globals(), *USE_CASES, "EXAMPLES", "EXTRAS", "missing_modules"})
