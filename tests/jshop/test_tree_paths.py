"""A node's path spells its ancestors, so a recursion thousands deep made
the paths quadratic in the plan's length: IPC 2020 Towers pfile_10 (1,023
moves, nodes hundreds of levels down) printed 17.6 MB of JSON, pfile_15 took
24 GB. Nodes below :data:`~htn.jshop.plans.tree.PATH_DEPTH` have no path,
in the planner's trees and in a plan file's tree read back alike."""

from __future__ import annotations

import json

import pytest

from htn.jshop.plans.planfile import read_plan_file
from htn.jshop.plans.tree import PATH_DEPTH

from conftest import SHARED, run_htn

TOWERS = SHARED / "corpus" / "ipc2020-to" / "Towers"


def _nodes(tree: dict) -> dict:
    return {n["id"]: n for n in tree["nodes"]}


def _depth(nodes: dict, node: dict) -> int:
    d = 0
    while node["parent"] is not None:
        node, d = nodes[node["parent"]], d + 1
    return d


@pytest.mark.corpus
@pytest.mark.parametrize("search", ["dfs", "gbfs"])
def test_paths_stop_at_the_depth_limit_and_the_json_stays_linear(search, tmp_path):
    if not (TOWERS / "pfile_08.hddl").is_file():
        pytest.skip(f"{TOWERS} not found")
    domain, problem = TOWERS / "domain.hddl", TOWERS / "pfile_08.hddl"
    done = run_htn("plan", domain, problem, "-q", "-f", "json", "--search", search)
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout.splitlines()[0])
    nodes = _nodes(record["tree"])
    depths = {i: _depth(nodes, n) for i, n in nodes.items()}
    assert max(depths.values()) > 2 * PATH_DEPTH  # Towers recurses deep
    for i, n in nodes.items():
        if n["parent"] is None:
            continue
        parts = n["path"].split("/") if n["path"] else []
        assert len(parts) == (depths[i] if depths[i] <= PATH_DEPTH else 0), (depths[i], n["path"])
        if 1 < depths[i] <= PATH_DEPTH:  # its parent's path and its own label
            assert n["path"].rsplit("/", 1)[0] == nodes[n["parent"]]["path"]
    # 255 moves: 1.27 MB with every path spelled out
    assert len(done.stdout) < 400_000, len(done.stdout)
    # written with its tree into a plan file, the tree reads back with the same paths
    plan = tmp_path / "plan.txt"
    assert run_htn("plan", domain, problem, "-o", plan, "--search", search).returncode == 0
    read = read_plan_file(str(plan))
    tree = read.tree(0)
    assert tree is not None
    paths, work = [], [tree]
    while work:
        t = work.pop()
        paths += [c.path for c in t.children]
        work += t.children
    assert sorted(paths) == sorted(n["path"] for n in nodes.values() if n["parent"] is not None)
