"""Record and replay (issue 36): ``htn ros record`` writes an htn node's
topics into a rosbag2 bag, and ``htn view`` shows a goal of the bag as it
shows the log of ``htn run --log``.

The reader (:mod:`htn.view.bag`) is tested on bags that ``rosbags`` writes
here, without ROS (skipped without rosbags); the recorder against a real
node, a real ``htn ros send`` and real ``htn ros record`` processes (slow,
skipped without the ros extra)."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
from importlib.util import find_spec

import pytest

from htn import missing_modules
from htn.jshop.language.errors import HtnError

import rosenv
from conftest import ROOT, run_htn, start_htn, wait_until

DOMAIN, PROBLEM = ROOT / "domains" / "domestic.jshop", ROOT / "problems" / "bring_object.jshop"
GOAL = "((bring_object jenny pringles guest))"
EVENT, FACTS = "htn_interfaces/msg/Event", "htn_interfaces/msg/Facts"

needs_rosbags = pytest.mark.skipif(
    find_spec("rosbags") is None, reason="needs rosbags (the ros extra): pip install 'htn[ros]'"
)
needs_view = pytest.mark.skipif(
    bool(missing_modules("view")), reason="needs the view extra: pip install 'htn[view]'"
)
ROS = [pytest.mark.slow, pytest.mark.ros]  # the tests that start ROS processes


# ---------------------------------------------------------------- bags written here


@pytest.fixture(scope="module")
def goals():
    """The records of two runs of the domestic goal, as htn run --log logs them."""
    import htn

    plan = next(iter(htn.plan(DOMAIN, PROBLEM)))
    return [
        htn.run(plan, robot="symbolic", domain=DOMAIN, problem=PROBLEM, seed=s).events
        for s in (1, 2)
    ]


def write_bag(path, texts, storage="sqlite3", topic="/htn/events", msgtype=EVENT):
    """A bag at ``path`` whose ``topic`` holds one Event per text of
    ``texts`` (its ``record``; a dict is dumped as the node does)."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    from htn.ros.record import typestore

    store = typestore()
    with Writer(path, version=9, storage_plugin=StoragePlugin[storage.upper()]) as writer:
        conn = writer.add_connection(topic, msgtype, typestore=store)
        for k, text in enumerate(texts):
            if msgtype == EVENT:
                text = text if isinstance(text, str) else json.dumps(text, default=str)
                msg = store.types[EVENT](
                    t=0.0,
                    sim_t=0.0,
                    step=-1,
                    action="",
                    event="x",
                    attempt=0,
                    detail="",
                    record=text,
                )
            else:
                msg = store.types[msgtype](data=str(text))
            writer.write(conn, 1000 + k, store.serialize_cdr(msg, msgtype))
    return path


def _dumped(records):
    """Records as they come back from JSON (tuples become lists)."""
    return json.loads(json.dumps(records, default=str))


@needs_rosbags
@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_bag_reads_back_as_the_logs_of_its_goals_the_last_by_default(tmp_path, goals, storage):
    from htn.view.bag import read_bag

    first, second = _dumped(goals[0]), _dumped(goals[1])
    assert first[0]["event"] == "header" and first[-1]["event"] == "summary"
    bag = write_bag(tmp_path / "session", [*first, *second], storage)
    last = read_bag(bag)
    assert last.records == second and (last.goal, last.goals, last.warning) == (2, 2, None)
    assert last.note == "goal 2 of 2; --goal N shows another"
    assert read_bag(bag, 1).records == first
    # the storage file alone is a bag too
    (store,) = bag.glob("*.db3" if storage == "sqlite3" else "*.mcap")
    assert read_bag(store, 1).records == first


@needs_rosbags
@needs_view
def test_the_view_use_case_takes_a_bag_and_its_goal(tmp_path, goals):
    from htn.api.view import read_view_log

    bag = write_bag(tmp_path / "session", [*_dumped(goals[0]), *_dumped(goals[1])])
    log = read_view_log(bag, goal=1)
    assert log.records == _dumped(goals[0]) and log.note.startswith("goal 1 of 2")
    jsonl = tmp_path / "run.jsonl"
    jsonl.write_text("".join(json.dumps(r) + "\n" for r in _dumped(goals[0])))
    with pytest.raises(HtnError, match=r"--goal chooses a goal of a rosbag2 bag"):
        read_view_log(jsonl, goal=1)
    assert read_view_log(jsonl).note is None


@needs_rosbags
def test_a_recording_that_began_during_a_goal_or_did_not_end_is_read_with_a_warning(
    tmp_path, goals
):
    from htn.view.bag import read_bag

    first, second = _dumped(goals[0]), _dumped(goals[1])
    late = read_bag(write_bag(tmp_path / "late", [*first[-3:], *second]))
    assert late.records == second and late.goals == 1 and late.note is None
    assert late.warning == (
        f"{tmp_path / 'late'}: 3 events before the first goal's header "
        "(the recording began during a goal) left out"
    )
    # a recorder killed: its folder has no metadata.yaml, its database what it committed
    killed = write_bag(tmp_path / "killed", first)
    (killed / "metadata.yaml").unlink()
    got = read_bag(killed)
    assert (
        got.records == first
        and "no metadata.yaml (the recording did not end in order" in got.warning
    )


BAD = [
    ("empty folder", None, r"not a rosbag2 bag: the folder has no metadata\.yaml"),
    ("garbage.db3", b"SQLite format 2\0" + bytes(range(256)) * 8, r"not a readable rosbag2 bag"),
    ("garbage.mcap", b"\x89MCAP0\r\n" + b"x" * 100, r"not a readable rosbag2 bag"),
    ("bad yaml", "metadata.yaml", r"not a readable rosbag2 bag"),
    (
        "no events",
        [("/chatter", "std_msgs/msg/String", ["hi"])],
        r"the bag holds no htn events \(no topic of type htn_interfaces/msg/Event; its topics: "
        r"/chatter \(std_msgs/msg/String\)\)",
    ),
    (
        "nothing recorded",
        [("/htn/events", EVENT, [])],
        r"the bag holds no events on /htn/events \(nothing was recorded\)",
    ),
    (
        "not json",
        [("/htn/events", EVENT, ['{"event": "header"}', '{"event": "tree", '])],
        r"/htn/events message 2: its record is not JSON: ",
    ),
    (
        "no event",
        [("/htn/events", EVENT, ['{"event": "header"}', "[1, 2]"])],
        r'/htn/events message 2: its record is no event of htn run --log \(no "event"\)',
    ),
    (
        "no header",
        [("/htn/events", EVENT, ['{"event": "start"}', '{"event": "summary"}'])],
        r"no goal's header among the bag's 2 events",
    ),
]


@needs_rosbags
@pytest.mark.parametrize("name,content,message", BAD, ids=[b[0] for b in BAD])
def test_a_bad_bag_is_one_located_error(tmp_path, name, content, message):
    from htn.view.bag import read_bag

    path = tmp_path / name.replace(" ", "_")
    if content is None:
        path.mkdir()
    elif isinstance(content, bytes):
        path.write_bytes(content)
    elif content == "metadata.yaml":
        path.mkdir()
        (path / "metadata.yaml").write_text("rosbag2_bagfile_information: [unclosed\n")
    else:
        ((topic, msgtype, texts),) = content
        write_bag(path, texts, topic=topic, msgtype=msgtype)
    with pytest.raises(HtnError) as error:
        read_bag(path)
    assert error.value.file == str(path) and error.value.line is None
    assert re.match(message, error.value.message), error.value.message
    if not missing_modules("view"):  # the command line: one line, exit 2
        r = run_htn("view", path)
        assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
        assert r.stderr.count("\n") == 1 and r.stderr.startswith(f"{path}: "), r.stderr


@needs_rosbags
def test_a_goal_the_bag_has_not_and_a_missing_bag_are_errors(tmp_path, goals):
    from htn.view.bag import read_bag

    bag = write_bag(tmp_path / "one", _dumped(goals[0]))
    with pytest.raises(HtnError, match=r"--goal 2: the bag holds 1 goal \(--goal 1 to 1\)"):
        read_bag(bag, 2)
    with pytest.raises(HtnError, match="no such bag or log file"):
        read_bag(tmp_path / "missing.db3")


def test_without_rosbags_reading_a_bag_names_the_extra(tmp_path, monkeypatch):
    import htn.view.bag as bag

    monkeypatch.setattr(bag, "find_spec", lambda name: None)
    (tmp_path / "b").mkdir()
    with pytest.raises(HtnError) as error:
        bag.read_bag(tmp_path / "b")
    assert str(error.value) == (
        f"{tmp_path / 'b'}: reading a rosbag2 bag needs rosbags: "
        "pip install 'htn[ros]' (or pip install rosbags)"
    )


def test_a_log_is_never_taken_for_a_bag_and_reading_one_loads_no_rosbags(tmp_path):
    from htn.view.bag import is_bag

    assert not is_bag(tmp_path / "run.jsonl") and not is_bag(tmp_path / "run.db3.jsonl")
    assert is_bag(tmp_path) and is_bag(tmp_path / "x.mcap") and is_bag(tmp_path / "x.DB3")
    code = (
        "import sys\nfrom htn.api.view import read_view_log\n"
        f"read_view_log({str(tmp_path / 'run.jsonl')!r})\n"
        "print(sorted(m for m in sys.modules if m.startswith(('rosbags', 'rclpy'))))"
    )
    (tmp_path / "run.jsonl").write_text('{"event": "header"}\n{"event": "summary"}\n')
    if missing_modules("view"):
        pytest.skip("needs the view extra: pip install 'htn[view]'")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0 and r.stdout.strip() == "[]", r.stderr


@needs_rosbags
@needs_view
def test_htn_view_serves_the_chosen_goal_of_a_bag(tmp_path, goals):
    from websockets.sync.client import connect

    first = _dumped(goals[0])
    bag = write_bag(tmp_path / "session", [*first, *_dumped(goals[1])])
    proc = start_htn("view", bag, "--goal", "1")
    try:
        line = proc.stderr.readline()
        match = re.fullmatch(r"view: http://127\.0\.0\.1:(\d+)/\?token=([\w-]+)\n", line)
        assert match, line
        assert proc.stderr.readline() == (
            f"view: {len(first)} events of {bag} (goal 1 of 2; "
            "--goal N shows another); Ctrl-C stops the server\n"
        )
        port, token = match.groups()
        with connect(
            f"ws://127.0.0.1:{port}/ws?token={token}", open_timeout=10, max_size=None
        ) as ws:
            hello = json.loads(ws.recv(timeout=10))
            assert hello["mode"] == "log" and hello["events"] == len(first)
            got = []
            while len(got) < len(first):
                got += json.loads(ws.recv(timeout=10))["events"]
        assert got == first
    finally:
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    assert proc.returncode == 0 and "Traceback" not in err, err


# ---------------------------------------------------------------- the recorder


@pytest.mark.skipif(find_spec("rclpy") is None, reason="the ros extra is not installed: no rclpy")
def test_an_output_that_exists_is_refused_and_left_as_it_was(tmp_path):
    (tmp_path / "bag").mkdir()
    (tmp_path / "bag" / "kept.txt").write_text("mine")
    (tmp_path / "file").write_text("mine too")
    for existing in ("bag", "file"):
        r = run_htn("ros", "record", tmp_path / existing)
        assert r.returncode == 2 and "Traceback" not in r.stderr
        assert r.stderr == (
            f"{tmp_path / existing}: already exists: htn ros record writes a new "
            "bag and replaces nothing (give another name)\n"
        )
    assert [p.name for p in (tmp_path / "bag").iterdir()] == ["kept.txt"]
    assert (tmp_path / "file").read_text() == "mine too"
    r = run_htn("ros", "record", tmp_path / "no" / "such" / "bag")
    assert r.returncode == 2 and "no such folder" in r.stderr


@pytest.fixture(scope="module")
def ros():
    return rosenv.ready("test_record")


FACTS_PUBLISHER = """
import rclpy
from htn.ros.interfaces import import_interfaces
T = import_interfaces()
rclpy.init()
node = rclpy.create_node("test_facts")
pub = node.create_publisher(T.Facts, "/htn/facts", 10)
while pub.get_subscription_count() < 3:         # the node and the two recorders
    rclpy.spin_once(node, timeout_sec=0.05)
pub.publish(T.Facts(add=[], remove=[], source="test"))
rclpy.spin_once(node, timeout_sec=0.5)
node.destroy_node()
rclpy.shutdown()
"""


def _recorder(ros, tmp_path, name):
    err = open(tmp_path / f"{name}.err", "w")
    proc = subprocess.Popen(
        [sys.executable, "-m", "htn", "ros", "record", tmp_path / name],
        env=ros,
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=err,
        text=True,
    )
    return proc, tmp_path / f"{name}.err"


@pytest.mark.slow
@pytest.mark.ros
def test_a_recorded_goal_is_the_nodes_log_and_a_killed_recorder_keeps_what_it_wrote(ros, tmp_path):
    from htn.view.bag import read_bag

    logs = tmp_path / "logs"
    logs.mkdir()
    node = start_htn(
        "ros",
        "node",
        DOMAIN,
        "--problem",
        PROBLEM,
        "--robot",
        "symbolic",
        "--log-dir",
        logs,
        env=ros,
    )
    recorders = [_recorder(ros, tmp_path, "stopped"), _recorder(ros, tmp_path, "killed")]
    try:
        for proc, err in recorders:
            wait_until(
                lambda err=err: "record: /htn/events: 1 publisher\n" in err.read_text(),
                "the recorder finds the node's events",
                proc,
                timeout=60,
            )
        sent = subprocess.run(
            [sys.executable, "-m", "htn", "ros", "send", GOAL],
            env=ros,
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert sent.returncode == 0, sent.stderr
        facts = subprocess.run(
            [sys.executable, "-c", FACTS_PUBLISHER],
            env=ros,
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert facts.returncode == 0, facts.stderr
        log = [json.loads(line) for line in (logs / "goal-0001.jsonl").read_text().splitlines()]

        def committed(bag):  # read while the recorder still runs
            try:
                return read_bag(bag).records[-1]["event"] == "summary"
            except HtnError:
                return False

        for proc, err in recorders:
            wait_until(
                lambda err=err: committed(tmp_path / err.stem), "the summary in the bag", proc
            )
        stopped, killed = (proc for proc, _ in recorders)
        stopped.send_signal(signal.SIGINT)
        killed.kill()
        out, _ = stopped.communicate(timeout=30)
        killed.communicate(timeout=30)
    finally:
        node.send_signal(signal.SIGINT)
        node.communicate(timeout=30)
        for proc, _ in recorders:
            if proc.poll() is None:
                proc.kill()
    err = (tmp_path / "stopped.err").read_text()
    assert stopped.returncode == 0 and "Traceback" not in err, err
    assert out == (
        f"recorded {len(log) + 1} messages ({len(log)} on /htn/events, 1 on "
        f"/htn/facts) in {tmp_path / 'stopped'}\n"
    )
    assert log[0]["event"] == "header" and log[-1]["event"] == "summary"
    # the bag holds the goal's events, each its log line, in order: nothing else is needed
    whole = read_bag(tmp_path / "stopped")
    assert whole.records == log and whole.warning is None and whole.goals == 1
    assert (tmp_path / "stopped" / "metadata.yaml").is_file()
    # killed: no metadata.yaml, but the database holds every event committed
    cut = read_bag(tmp_path / "killed")
    assert cut.records == log and "no metadata.yaml" in cut.warning
    assert not (tmp_path / "killed" / "metadata.yaml").exists()
    # the definitions and hashes recorded are those of the types the node publishes
    from rosbags.rosbag2 import Reader

    with Reader(tmp_path / "stopped") as reader:
        kinds = {c.topic: (c.msgtype, c.digest, c.msgcount) for c in reader.connections}
    assert {t: k[0] for t, k in kinds.items()} == {"/htn/events": EVENT, "/htn/facts": FACTS}
    assert kinds["/htn/events"][2] == len(log) and kinds["/htn/facts"][2] == 1
    assert all(k[1].startswith("RIHS01_") for k in kinds.values())
