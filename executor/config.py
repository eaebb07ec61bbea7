"""Execution settings: per-operator retry limits from a TOML file next to the
domain (``domains/domestic.jshop`` -> ``domains/domestic.toml``), overridable
on the command line (``--retries grasp=3``).

A domain without such a file gets :data:`DEFAULT_RETRIES` for every operator:
an action whose monitor did not verify it is tried once more before the run
(or ``--replan``) gives up on it, as a robot operator would. A file states
its limits itself: an operator it does not name gets no retry.
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Iterable

from htn.jshop.language.errors import HtnError


def config_path(domain_path: str) -> str:
    return os.path.splitext(domain_path)[0] + ".toml"


DEFAULT_RETRIES = 1  # per operator, for a domain without a .toml


def load_retries(domain_path: str | None, operators: Iterable[str] = ()) -> dict[str, int]:
    """Retry limits by operator name ('!grasp'). Without a file beside the
    domain (or without a domain file: a domain built in memory):
    :data:`DEFAULT_RETRIES` for each of ``operators`` (names; the internal
    ``!!`` ones, which are never retried, left out)."""
    path = config_path(domain_path) if domain_path else None
    if path is None or not os.path.isfile(path):
        return {op: DEFAULT_RETRIES for op in operators if not op.startswith("!!")}
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise HtnError(f"bad TOML: {exc}", path) from exc
    retries = data.get("retries", {})
    out = {}
    for name, n in retries.items():
        if not isinstance(n, int) or n < 0:
            raise HtnError(f"retries.{name} must be a non-negative integer", path)
        out[_op(name)] = n
    return out


def parse_overrides(items: Iterable[str]) -> dict[str, int]:
    """``grasp=3`` or ``!grasp=3`` pairs from ``--retries``."""
    out = {}
    for item in items:
        for part in item.split(","):
            name, sep, value = part.partition("=")
            if not sep or not name.strip():
                raise HtnError(f"--retries: expected OPERATOR=N, got '{part}'")
            try:
                n = int(value)
            except ValueError:
                raise HtnError(f"--retries: '{value}' is not a whole number") from None
            if n < 0:
                raise HtnError(f"--retries: {part} must not be negative")
            out[_op(name.strip())] = n
    return out


def _op(name: str) -> str:
    name = name.lower()
    return name if name.startswith("!") else "!" + name
