"""The caches of compiled code, and one way to forget them all.

The code generators (:mod:`~htn.jshop.logic.compile`,
:mod:`~htn.jshop.logic.modes`, :mod:`~htn.jshop.logic.engine`, ...) and the
grounding keep what they make keyed by the domain's own objects: an
:class:`IdentityCache` per kind of thing. That is right for one planning
run per process (the command line); a long-lived process that reads many
domains (the unified-planning engine, a robot's node) calls
:func:`clear_caches` between domains, and every cache has a bound besides,
so that memory stays flat whatever the caller does.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any

_REGISTERED: list = []
_HOOKS: list = []

LIMIT = 200_000  # entries of one cache: past it the cache starts again empty


class IdentityCache:
    """Values keyed by an object's identity.

    Each entry keeps its object alive beside the value, and a lookup checks
    that the entry is that object's: an ``id`` that Python gave again to a
    new object never returns a value made for a dead one. ``key`` adds
    parts to the identity (a mode, a kind); it is ``id(obj)`` alone when
    not given, and must contain ``id(obj)`` when it is.

    A module-level cache (``global_=True``, the default) is emptied by
    :func:`clear_caches`; one owned by an object (a grounding) goes with
    it. Past ``limit`` entries a cache is emptied and fills again.
    """

    __slots__ = ("entries", "limit", "__weakref__")

    def __init__(self, limit: int = LIMIT, global_: bool = True):
        self.entries: dict = {}
        self.limit = limit
        if global_:
            _REGISTERED.append(self)

    def get(self, obj, key: Hashable | None = None, default: Any = None) -> Any:
        """The value kept for ``obj`` (under ``key``), else ``default``."""
        hit = self.entries.get(id(obj) if key is None else key)
        if hit is not None and hit[0] is obj:
            return hit[1]
        return default

    def put(self, obj, value, key: Hashable | None = None):
        """Keep ``value`` for ``obj`` (under ``key``); returns it."""
        if len(self.entries) >= self.limit:
            self.entries.clear()
        self.entries[id(obj) if key is None else key] = (obj, value)
        return value

    def make(self, obj, build: Callable[[], Any], key: Hashable | None = None):
        """The value kept for ``obj``, made with ``build()`` the first time."""
        hit = self.entries.get(id(obj) if key is None else key)
        if hit is not None and hit[0] is obj:
            return hit[1]
        return self.put(obj, build(), key)

    def clear(self) -> None:
        self.entries.clear()

    def __len__(self) -> int:
        return len(self.entries)


def cache(limit: int = LIMIT) -> IdentityCache:
    """A new module-level cache that :func:`clear_caches` empties."""
    return IdentityCache(limit)


def on_clear(hook) -> None:
    """Call ``hook()`` too when the caches are cleared."""
    _HOOKS.append(hook)


def clear_caches() -> None:
    """Forget every compiled function (and its source, see ``codegen``)."""
    for c in _REGISTERED:
        c.clear()
    for hook in _HOOKS:
        hook()
