"""The caches of compiled code, and one way to forget them all.

The code generators (:mod:`~htn.jshop.logic.compile`,
:mod:`~htn.jshop.logic.modes`, :mod:`~htn.jshop.logic.engine`) keep what they
compile keyed by the domain's objects, which is right for one planning run
per process (the command line) but not for a long-lived process that parses
many domains: such a process calls :func:`clear_caches` between domains.
"""
from __future__ import annotations

_REGISTERED: list[dict] = []
_HOOKS: list = []


def cache() -> dict:
    """A new cache that :func:`clear_caches` empties."""
    d: dict = {}
    _REGISTERED.append(d)
    return d


def on_clear(hook) -> None:
    """Call ``hook()`` too when the caches are cleared."""
    _HOOKS.append(hook)


def clear_caches() -> None:
    """Forget every compiled function (and its source, see ``codegen``)."""
    for d in _REGISTERED:
        d.clear()
    for hook in _HOOKS:
        hook()
