"""The one place where htn meets two lark versions: lark 1.x (what htn
declares) and lark-parser 0.12, the same module under an older name, which
ROS 2's wheels (the ros extra) bring and which pip installs over lark 1.x's
files when it is added to a virtualenv that has them. The readers work with
both, so that adding the ros extra never breaks planning.

What differs for htn's readers: a callback under ``v_args(meta=True)`` gets
``(meta, children)`` from lark 1.x and ``(children, meta)`` from 0.12
(:func:`with_meta` passes ``(meta, children)`` under both).
"""

from __future__ import annotations

import functools

from lark import v_args
from lark.tree import Meta


def with_meta(fn):
    """``v_args(meta=True)`` that calls ``fn(self, meta, children)`` under
    every lark version."""

    @functools.wraps(fn)
    def call(self, first, second):
        if isinstance(first, Meta):
            return fn(self, first, second)
        return fn(self, second, first)

    return v_args(meta=True)(call)
