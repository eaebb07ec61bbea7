"""UP's own hierarchical test cases, shared by the tests of htn.up.

``up_test_cases`` (shipped with unified-planning) is run by UP as a script
from its own folder (``report.py``), so its packages import ``utils`` as a
top-level module: the folder is appended to ``sys.path`` the same way.
"""

from __future__ import annotations

import os
import sys
from functools import lru_cache

import pytest

pytest.importorskip("unified_planning")

# the hierarchical cases whose kind htn declares, and those it refuses
SUPPORTED = [f"htn:opti-action-costs-{i}" for i in range(8)] + ["test:htn-go"]
REFUSED = ["test:htn-go-temporal"]


@lru_cache(maxsize=1)
def cases() -> dict:
    """Name -> UP ``TestCase``: ``builtin.hierarchical`` and UP's examples."""
    import unified_planning.test as up_test
    import up_test_cases

    folder = os.path.dirname(up_test_cases.__file__)
    if folder not in sys.path:
        sys.path.append(folder)
    import builtin.hierarchical as hierarchical

    out = dict(hierarchical.get_test_cases())
    out.update(up_test.get_test_cases())
    return out


def report_script() -> str:
    import up_test_cases

    return os.path.join(os.path.dirname(up_test_cases.__file__), "report.py")


# ---------------------------------------------------------------- tests


def test_the_lists_name_every_hierarchical_case_and_agree_with_the_kind():
    from unified_planning.model.htn import HierarchicalProblem
    from unified_planning.shortcuts import OneshotPlanner

    import htn.up  # noqa: F401

    hierarchical = {
        name for name, tc in cases().items() if isinstance(tc.problem, HierarchicalProblem)
    }
    assert hierarchical == set(SUPPORTED) | set(REFUSED)
    with OneshotPlanner(name="htn") as planner:
        for name, tc in cases().items():
            assert planner.supports(tc.problem.kind) == (name in SUPPORTED), name
