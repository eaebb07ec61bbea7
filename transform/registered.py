"""The framework with the registered rules: the three of the paper
(:mod:`htn.transform.rules`, priorities tray > container > both-hands) and
those of plugins (the entry-point group ``htn.transformations`` names
functions called with the framework to register theirs), and the paper's
module-level API over it."""

from __future__ import annotations

from . import rules
from .framework import Framework, Workspace

_DEFAULT: Framework | None = None


def default_framework() -> Framework:
    """The framework with the three built-in rules and any plugins registered,
    priorities tray > container > both-hands."""
    global _DEFAULT
    if _DEFAULT is None:
        fw = Framework()
        rules.register(fw)
        _load_plugins(fw)
        _DEFAULT = fw
    return _DEFAULT


def _load_plugins(fw: Framework) -> None:
    from importlib.metadata import entry_points

    for ep in entry_points(group="htn.transformations"):
        ep.load()(fw)


def register_transformation(function, applicability_rule, name=None):
    return default_framework().register_transformation(function, applicability_rule, name)


def disable_transformation(which):
    default_framework().disable_transformation(which)


def enable_transformation(which):
    default_framework().enable_transformation(which)


def prioritize_transformation(superior, inferior):
    default_framework().prioritize_transformation(superior, inferior)


def apply_all_transformations(ws: Workspace, metric: str = "navigation") -> Workspace:
    return default_framework().apply_all_transformations(ws, metric)
