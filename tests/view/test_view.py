"""The browser view without a browser: the task tree in the log (``tree``
events, ``node`` on every action event), reading logs for ``htn view``, the
token, and the hand-over from the robot's thread that never waits for a page.
The page itself is tested in a real browser: tests/view/test_view_browser.py."""

from __future__ import annotations

import json
import re
import signal
import socket
import threading
import urllib.error
import urllib.request

import pytest

from htn import missing_modules
from htn.executor.dispatcher import TaskDispatcher
from htn.executor.log import EventLog
from htn.jshop import Planner, load_domain, load_problem
from htn.jshop.language.errors import HtnError
from htn.robot.backends import RobotRequest, make_robot
from htn.view.model import page_records, read_log

from conftest import ROOT, run_htn, start_htn, wait_until

needs_view = pytest.mark.skipif(
    bool(missing_modules("view")), reason="needs the view extra: pip install 'htn[view]'"
)
KITCHEN = ROOT / "domains" / "kitchen.jshop"
SET_TABLE = ROOT / "problems" / "set_table_and_clean_up.jshop"


def kitchen_run(faults="effect=0.2", seed=2, replan=True, path=None):
    """A symbolic run of the kitchen's set-the-table problem (seed 2: 9 repairs)."""
    dom = load_domain(str(KITCHEN))
    inst = load_problem(str(SET_TABLE)).instances[0]
    plan = next(Planner(dom, inst, record_trees=True).plans())
    robot = make_robot("symbolic", RobotRequest(dom, inst, faults, seed))
    log = EventLog(path, clock=lambda: robot.sim_time)
    summary = TaskDispatcher(
        robot, dom, inst, plan.steps, {}, log, replan=replan, tree=plan.tree
    ).run()
    log.close()
    return plan, log.events, summary


def logged_run(tmp_path):
    """The log of a real ``htn run`` (symbolic kitchen robot, faults, repairs)."""
    plan, log = tmp_path / "plan.txt", tmp_path / "run.jsonl"
    assert run_htn("plan", KITCHEN, SET_TABLE, "-o", plan).returncode == 0
    r = run_htn(
        "run",
        plan,
        "--robot",
        "symbolic",
        "--faults",
        "effect=0.2",
        "--seed",
        2,
        "--replan",
        "--log",
        log,
    )
    assert r.returncode == 0, r.stderr
    return log


def test_the_log_holds_the_task_tree_and_every_graft():
    plan, events, summary = kitchen_run()
    assert summary.result == "verified" and summary.replans >= 2
    trees = [e for e in events if e["event"] == "tree"]
    assert events[0]["event"] == "tree" and len(trees) == 1 + summary.replans
    # the first: the plan's task tree, node for node, depth first
    first = trees[0]["nodes"]
    walked = list(plan.tree.walk())
    assert [n["task"] for n in first] == [
        t.task if t.step is None else str(plan.steps[t.step]) for t in walked
    ]
    assert [n["id"] for n in first] == list(range(len(walked)))
    assert first[0]["parent"] is None and all(n["parent"] < n["id"] for n in first[1:])
    steps = {n["id"]: n["step"] for n in first if "step" in n}
    assert sorted(steps.values()) == list(range(1, len(plan.steps) + 1))
    known = {n["id"]: n for n in first}
    for k, ev in enumerate(events):
        if ev["event"] == "tree" and ev is not trees[0]:
            assert events[k - 1]["event"] == "replanned"  # right after its repair
            ids = [n["id"] for n in ev["nodes"]]
            assert ids == list(range(len(known), len(known) + len(ids)))  # fresh numbers
            assert ev["replaces"] and set(ev["replaces"]) <= set(known)
            assert ev["parent"] in known
            assert all(known[r]["parent"] == ev["parent"] for r in ev["replaces"])
            tops = [n for n in ev["nodes"] if n["parent"] == ev["parent"]]
            assert tops and all(n["parent"] in known or n["parent"] in ids for n in ev["nodes"])
            known.update({n["id"]: n for n in ev["nodes"]})
        elif ev["step"] is not None:
            # every event about an action names its node, and that node is the action
            node = known[ev["node"]]
            assert node["task"] == ev["action"], ev
    # an action of the tree as first logged runs as the step it was numbered
    starts = {e["node"]: e["step"] for e in events if e["event"] == "start"}
    first_graft = next(k for k, e in enumerate(events) if e["event"] == "replanned")
    before = [e for e in events[:first_graft] if e["event"] == "start"]
    assert before and all(steps[e["node"]] == e["step"] for e in before)
    assert len(starts) >= len(plan.steps)


def test_a_plan_without_a_task_tree_has_one_node_per_step():
    dom = load_domain(str(KITCHEN))
    inst = load_problem(str(SET_TABLE)).instances[0]
    plan = next(Planner(dom, inst).plans())
    robot = make_robot("symbolic", RobotRequest(dom, inst))
    log = EventLog(None, clock=lambda: robot.sim_time)
    TaskDispatcher(robot, dom, inst, plan.steps, {}, log).run()
    (tree,) = [e for e in log.events if e["event"] == "tree"]
    assert [n["task"] for n in tree["nodes"][1:]] == [str(s) for s in plan.steps]
    assert all(n["parent"] == 0 for n in tree["nodes"][1:])


def _write(path, records, tail="\n"):
    path.write_text("\n".join(json.dumps(r) for r in records) + tail)


def test_a_log_is_read_whole_or_refused_at_its_line(tmp_path):
    _, events, _ = kitchen_run()
    header = {
        "t": 0.0,
        "sim_t": 0.0,
        "step": None,
        "action": None,
        "event": "header",
        "attempt": None,
        "detail": "",
        "plan": "/x/plan.txt",
        "robot": "symbolic",
    }
    good = tmp_path / "run.jsonl"
    _write(good, [header, *events])
    records, warning = read_log(str(good))
    assert records == [header, *events] and warning is None
    # a run killed while it wrote its last line: that line is left out, with a warning
    cut = tmp_path / "cut.jsonl"
    cut.write_text(good.read_text()[:-30])
    records, warning = read_log(str(cut))
    assert len(records) == len(events) and "incomplete" in warning
    bad = tmp_path / "bad.jsonl"
    lines = good.read_text().splitlines()
    bad.write_text("\n".join([lines[0], lines[1], "{not json", *lines[2:]]) + "\n")
    with pytest.raises(HtnError) as err:
        read_log(str(bad))
    assert (err.value.line, err.value.col) == (3, 2)
    headless = tmp_path / "headless.jsonl"
    _write(headless, events)
    with pytest.raises(HtnError, match="no header"):
        read_log(str(headless))


def test_a_log_without_tree_events_is_shown_by_step():
    _, events, _ = kitchen_run(faults="", replan=False)
    header = {
        "t": 0.0,
        "sim_t": 0.0,
        "step": None,
        "action": None,
        "event": "header",
        "attempt": None,
        "detail": "",
    }
    old = [header] + [
        {k: v for k, v in e.items() if k != "node"} for e in events if e["event"] != "tree"
    ]
    shown = page_records(old)
    assert shown[1]["event"] == "tree" and shown[1]["synthetic"]
    nodes = {n["id"]: n for n in shown[1]["nodes"]}
    assert shown[:1] + shown[2:] != old  # the events now name their nodes
    for rec in shown[2:]:
        if rec["step"] is not None:
            assert nodes[rec["node"]]["step"] == rec["step"]
    assert page_records(events) is events  # a log with its tree: as it is


# ------------------------------------------------------------------ the server


def _get(url):
    try:
        with urllib.request.urlopen(url, timeout=10) as response:
            return response.status, response.read().decode(), response.headers
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read().decode(), exc.headers


@needs_view
def test_htn_view_serves_only_requests_with_the_token(tmp_path):
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    log = logged_run(tmp_path)
    lines = log.read_text().splitlines()
    proc = start_htn("view", log)
    try:
        line = proc.stderr.readline()
        match = re.fullmatch(r"view: (http://127\.0\.0\.1:(\d+)/\?token=([\w-]+))\n", line)
        assert match, line
        url, port, token = match.groups()
        base = f"http://127.0.0.1:{port}"
        status, text, headers = _get(url)
        assert status == 200 and f"static/app.js?token={token}" in text
        assert "default-src 'self'" in headers["Content-Security-Policy"]
        assert _get(f"{base}/static/app.js?token={token}")[0] == 200
        for bad in (
            f"{base}/",
            f"{base}/?token=x{token}",
            f"{base}/static/app.js",
            f"{base}/static/tree.js?token=",
            f"{base}/ws",
        ):
            status, text, _ = _get(bad)
            assert status == 403 and "token" in text, bad
        with pytest.raises(InvalidStatus) as refused:
            connect(f"ws://127.0.0.1:{port}/ws?token=wrong", open_timeout=10)
        assert refused.value.response.status_code == 403
        with connect(
            f"ws://127.0.0.1:{port}/ws?token={token}", open_timeout=10, max_size=None
        ) as ws:
            hello = json.loads(ws.recv(timeout=10))
            assert hello["type"] == "hello" and hello["mode"] == "log"
            got = []
            while len(got) < len(lines):
                message = json.loads(ws.recv(timeout=10))
                assert message["type"] == "events" and message["from"] == len(got)
                got += message["events"]
            assert got == [json.loads(x) for x in lines]
    finally:
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    assert "Traceback" not in err


@needs_view
def test_a_page_that_does_not_read_never_blocks_the_robot_and_loses_no_event():
    """The robot's thread publishes while a page takes nothing: publishing
    never waits; later the page gets every event once, in order, and of the
    camera frames only some, the latest last."""
    from websockets.sync.client import connect

    from htn.view.hub import Hub
    from htn.view.server import ViewServer

    hub = Hub("live")
    server = ViewServer(hub).start()
    hub.begin([], "a run", camera=True, wall_start=None)
    port, token = server.port, server.token
    try:
        with connect(
            f"ws://127.0.0.1:{port}/ws?token={token}", open_timeout=10, max_size=None
        ) as ws:
            json.loads(ws.recv(timeout=10))  # hello
            wait_until(lambda: hub.pages == 1, "the page counted")
            frame = bytes(range(256)) * 400  # 100 kB: the socket fills fast
            done = threading.Event()

            def robot():
                for k in range(30000):
                    hub.publish({"event": "feedback", "k": k, "detail": "x" * 100})
                    if k % 150 == 0:
                        hub.set_frame(frame + k.to_bytes(4, "big"), k / 100)
                done.set()

            threading.Thread(target=robot, daemon=True).start()
            # the page reads nothing meanwhile: megabytes wait in the socket, yet
            assert done.wait(30), "publishing blocked on a page that does not read"
            events, frames = [], []
            while (
                len(events) < 30000 or not frames or frames[-1][-4:] != (29850).to_bytes(4, "big")
            ):
                message = ws.recv(timeout=20)
                if isinstance(message, bytes):
                    frames.append(message)
                    continue
                message = json.loads(message)
                if message["type"] == "events":
                    assert message["from"] == len(events)
                    events += message["events"]
        assert [e["k"] for e in events] == list(range(30000))
        assert 1 <= len(frames) < 200  # 200 frames were set: most were dropped
    finally:
        server.close()


@needs_view
def test_view_input_errors_are_one_line(tmp_path):
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"event": "header"}\n[1, 2]\n')
    r = run_htn("view", bad)
    assert r.returncode == 2 and re.search(r"bad\.jsonl:2:1: not an event", r.stderr), r.stderr
    r = run_htn("view", tmp_path / "missing.jsonl")
    assert r.returncode == 2 and "no such log file" in r.stderr
    r = run_htn("run", "plan.txt", "--robot", "symbolic", "--view-wait")
    assert r.returncode == 2 and "--view-wait" in r.stderr and "--view" in r.stderr
    plan = tmp_path / "plan.txt"
    run_htn("plan", KITCHEN, SET_TABLE, "-o", plan)
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        r = run_htn("run", plan, "--robot", "symbolic", "--view", "--view-port", port)
        assert r.returncode == 2, r.stderr
        assert f"cannot serve the view on 127.0.0.1 port {port}" in r.stderr
        assert "Traceback" not in r.stderr
        r = run_htn("view", plan, "--port", port)
    assert r.returncode == 2 and "plan.txt:1:1" in r.stderr, r.stderr


def test_only_a_loopback_address_is_served_without_a_warning(capsys):
    from htn.cli.view_cmd import _announce
    from htn.view.server import is_loopback

    assert all(map(is_loopback, ("127.0.0.1", "127.0.0.2", "::1", "localhost")))
    assert not any(map(is_loopback, ("0.0.0.0", "::", "192.168.1.5", "example.org")))
    _announce("http://127.0.0.1:1/?token=t", "127.0.0.1")
    assert capsys.readouterr().err == "view: http://127.0.0.1:1/?token=t\n"
    _announce("http://host:1/?token=t", "0.0.0.0")
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("warning: the view is served on 0.0.0.0, reachable from other")
    assert err[1] == "view: http://host:1/?token=t"
