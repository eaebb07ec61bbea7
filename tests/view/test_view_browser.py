"""The browser view in a real headless browser: Debian's chromium and
chromium-driver, driven by selenium (no browser is downloaded), against the
real ``htn run --view`` and ``htn view`` commands. What the page shows is
read from its DOM and checked against the log the run wrote.

A script given to the browser before any page script runs records every
change of a tree row's ``data-status`` and of the result, in order, so the
tests can tell that statuses changed as the run went, not only how they ended.

``HTN_VIEW_SCREENSHOT=docs/view-kitchen.png`` makes the kitchen test save its
screenshot there (the README's picture).
"""

from __future__ import annotations

import importlib.util
import json
import os
import queue
import re
import shutil
import signal
import statistics
import tempfile
import threading
import time

import pytest

from htn import missing_modules

from conftest import CORPUS, ROOT, needs_corpus, run_htn, start_htn

CHROMIUM, DRIVER = shutil.which("chromium"), shutil.which("chromedriver")
SELENIUM = importlib.util.find_spec("selenium") is not None
MISSING = [
    what
    for what, ok in (
        ("Debian's chromium (apt-get install chromium)", CHROMIUM),
        ("Debian's chromium-driver (apt-get install chromium-driver)", DRIVER),
        ("selenium (pip install selenium)", SELENIUM),
        ("the view extra (pip install 'htn[view]')", not missing_modules("view")),
    )
    if not ok
]
# a real browser per test: in the full suite, not in the fast subset
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(bool(MISSING), reason="the browser tests need " + ", ".join(MISSING)),
]

CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--window-size=1400,900",
)
BLOCKS = CORPUS / "blocks-smallproblem"
BLOCKS_BIG = CORPUS / "blocks-problem"
DOMESTIC, KITCHEN = ROOT / "domains" / "domestic.jshop", ROOT / "domains" / "kitchen.jshop"

RECORDER = """
(() => {
  const targets = [], ids = new WeakMap(), recs = [];
  window.__treeSizes = [];
  const take = list => {
    const now = performance.now();
    for (const r of list) {
      if (r.type === "attributes") {
        let k = ids.get(r.target);
        if (k === undefined) { k = targets.length; targets.push(r.target); ids.set(r.target, k); }
        recs.push([k, r.attributeName, r.oldValue, now]);
      } else if (r.target.id === "tree-count") {
        const n = parseInt(r.target.textContent);       // "4215 nodes · ..."
        window.__treeSizes.push([n, now]);
        // the frame after the next one starts once the next one (with the rows) is drawn
        requestAnimationFrame(() => requestAnimationFrame(
          () => window.__treeSizes.push([n, performance.now(), "painted"])));
      }
    }
  };
  const observer = new MutationObserver(take);
  observer.observe(document, {subtree: true, childList: true, attributes: true,
                              attributeFilter: ["data-status", "data-result"], attributeOldValue: true});
  // every change in order: [order, node id or null (the result), new value]
  window.__changes = () => {
    take(observer.takeRecords());
    const out = [];
    const last = new Map();
    recs.forEach(([k, attr, old], i) => {
      const prev = last.get(k + attr);
      if (prev !== undefined) out[prev][2] = old;
      last.set(k + attr, out.length);
      const el = targets[k];
      out.push([i, attr === "data-result" ? null : Number(el.dataset.node), null]);
    });
    for (const [key, at] of last) {
      const el = targets[recs[out[at][0]][0]];
      out[at][2] = out[at][1] === null ? el.dataset.result : el.dataset.status;
    }
    return out;
  };
})();
"""

# the status a node's row must show after each kind of event (None: no change)
STATUS_AFTER = {
    "start": "running",
    "finished": "finished",
    "verified": "verified",
    "aborted": "aborted",
    "failed": "failed",
    "retrying": "retrying",
    "interrupted": "interrupted",
}


@pytest.fixture(scope="module")
def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in CHROMIUM_FLAGS:
        options.add_argument(flag)
    profile = tempfile.mkdtemp(prefix="htn-view-chromium-")
    options.add_argument(f"--user-data-dir={profile}")
    driver = webdriver.Chrome(service=Service(DRIVER), options=options)
    driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": RECORDER})
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


class Served:
    """``htn run --view ...`` or ``htn view ...`` in a subprocess: its URL, then its end."""

    def __init__(self, *args):
        self.proc = start_htn(*args)
        self.lines: queue.Queue = queue.Queue()
        self.err: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()
        self.url = None
        deadline = time.monotonic() + 180
        while self.url is None:
            try:
                line = self.lines.get(timeout=max(0.1, deadline - time.monotonic()))
            except queue.Empty:
                self.proc.kill()
                pytest.fail("no view: line within 180 s: " + "".join(self.err))
            if line is None:
                pytest.fail(f"ended before its view: line: {''.join(self.err)}")
            match = re.fullmatch(r"view: (http://127\.0\.0\.1:\d+/\?token=[\w-]+)\n", line)
            self.url = match.group(1) if match else None

    def _read(self):
        for line in self.proc.stderr:
            self.err.append(line)
            self.lines.put(line)
        self.lines.put(None)

    def stop(self, after=None):
        """Ctrl-C (once stderr has said ``after``); returns (exit code, stdout, stderr)."""
        deadline = time.monotonic() + 120
        while after and not any(after in line for line in self.err):
            if time.monotonic() > deadline or self.proc.poll() is not None:
                pytest.fail(f"never said {after!r}: {''.join(self.err)}")
            time.sleep(0.05)
        self.proc.send_signal(signal.SIGINT)
        out = self.proc.stdout.read()
        self.proc.wait(timeout=60)
        return self.proc.returncode, out, "".join(self.err)


def plan_file(tmp_path, domain, problem):
    path = tmp_path / f"{problem.stem}.txt"
    r = run_htn("plan", domain, problem, "-o", path)
    assert r.returncode == 0, r.stderr
    return path


def read_log(path):
    return [json.loads(line) for line in path.read_text().splitlines()]


def tree_nodes(records):
    return [n for r in records if r["event"] == "tree" for n in r["nodes"]]


def expected_statuses(records):
    """Each action node's status after ``records``, as the log says."""
    status = {n["id"]: "pending" for n in tree_nodes(records) if "step" in n}
    for r in records:
        if r.get("node") in status and STATUS_AFTER.get(r["event"]):
            status[r["node"]] = STATUS_AFTER[r["event"]]
    return status


def wait_for(driver, script, what, timeout=180.0):
    deadline = time.monotonic() + timeout
    while True:
        value = driver.execute_script(script)
        if value:
            return value
        if time.monotonic() > deadline:
            pytest.fail(f"the page never showed {what}")
        time.sleep(0.05)


def page_nodes(driver):
    return {
        n["id"]: n
        for n in driver.execute_script("""
        return [...document.querySelectorAll('#tree .node')].map((r, i) => ({
          id: Number(r.dataset.node), index: i, task: r.querySelector('.task').textContent,
          status: r.dataset.status, kind: r.dataset.kind, depth: Number(r.dataset.depth),
          replaced: r.hasAttribute('data-replaced'),
          grafted: r.hasAttribute('data-grafted'), faults: Number(r.dataset.faults),
          badges: [...r.querySelectorAll('.badge')].map(b => b.textContent)}));""")
    }


def page_events(driver):
    return driver.execute_script("""
        return [...document.querySelectorAll('#timeline .ev')].map(r => ({
          seq: Number(r.dataset.seq), kind: r.dataset.kind, t: Number(r.dataset.t),
          shown: Number(r.dataset.shown), cls: r.className}));""")


def check_page(driver, records):
    """What the page shows once the run's last event is in: every node,
    statuses as the log ends, repairs, every event, faults on their nodes."""
    wait_for(
        driver,
        f"return document.querySelectorAll('#timeline .ev').length >= {len(records)}",
        f"all {len(records)} events",
    )
    driver.find_element("id", "expand-all").click()  # nothing out of reach
    nodes = page_nodes(driver)
    logged = tree_nodes(records)
    assert len(nodes) == len(logged)
    for n in logged:  # every node of the tree appears
        assert nodes[n["id"]]["task"] == n["task"], n
    shown = {i: n["status"] for i, n in nodes.items() if n["kind"] == "action"}
    assert shown == expected_statuses(records)  # statuses end as the log says
    for graft in (r for r in records if r["event"] == "tree" and r["replaces"]):
        new = [n for n in graft["nodes"]]
        for old in graft["replaces"]:  # the repaired subtree, shown replaced
            assert nodes[old]["replaced"] and any(
                b.startswith("replaced") for b in nodes[old]["badges"]
            )
        assert all(nodes[n["id"]]["grafted"] for n in new)  # and the new one present
        tops = [nodes[n["id"]] for n in new if n["parent"] == graft["parent"]]
        last_old = max(nodes[o]["index"] for o in graft["replaces"])
        assert min(t["index"] for t in tops) > last_old  # right after what it replaces
        assert {t["depth"] for t in tops} == {nodes[o]["depth"] for o in graft["replaces"]}
    rows = page_events(driver)  # the timeline lists every event
    assert [r["seq"] for r in rows] == list(range(len(records)))
    assert [r["kind"] for r in rows] == [r["event"] for r in records]
    faults = [r for r in records if r["event"] == "fault"]
    for f in faults:  # a fault is marked on its node
        node = nodes[f["node"]]
        assert node["faults"] >= 1 and any(f["kind"] in b for b in node["badges"]), node
    return nodes, rows


def check_live(driver, records, rows):
    """Statuses changed as the run went: every action that started was shown
    running before it was shown as it ended, and before the result was in."""
    changes = driver.execute_script("return window.__changes()")
    result_at = min(i for i, node, value in changes if node is None and value)
    seen: dict = {}
    for i, node, value in changes:
        if node is not None:
            seen.setdefault(node, []).append((i, value))
    final = expected_statuses(records)
    started = {r["node"] for r in records if r["event"] == "start"}
    assert started
    for node in started:
        values = [v for _, v in seen[node]]
        assert "running" in values and values[-1] == final[node], (node, values)
        assert values.index("running") < len(values) - 1
    ended = [i for node in started for i, v in seen[node] if v in ("verified", "aborted", "failed")]
    assert min(ended) < result_at
    wall_start = float(driver.execute_script("return document.body.dataset.wallStart"))
    first = next(k for k, r in enumerate(records) if r["event"] == "start")
    late = [row["shown"] - 1000 * (wall_start + row["t"]) for row in rows[first:]]
    return statistics.median(late), max(late), len(late)


# The target is 200 ms from an event to the page (and 2 s for a 1,000-node
# tree): that is measured and reported (report_latency; run these tests alone,
# -n 0, on a quiet machine). A test asserts behaviour, not speed: here, that
# events are shown live, within a second, also when the other test worker and
# the run share the two cores with the browser (265 ms seen so).
LIVE_MS = 1000


def report_latency(record_property, name, median, worst, n):
    print(
        f"\n{name}: {n} events reached the page {median:.0f} ms (median), "
        f"{worst:.0f} ms (max) after they happened"
    )
    record_property(f"{name}_latency_median_ms", round(median, 1))
    record_property(f"{name}_latency_max_ms", round(worst, 1))


@needs_corpus
def test_a_symbolic_run_with_repairs_live_in_the_browser(browser, tmp_path, record_property):
    plan = plan_file(tmp_path, BLOCKS / "blocks", BLOCKS / "smallproblem")
    log = tmp_path / "run.jsonl"
    # seed 2: a fault the default retry (1 per operator) does not absorb, so a repair
    run = Served(
        "run",
        plan,
        "--robot",
        "symbolic",
        "--faults",
        "effect=0.3",
        "--replan",
        "--seed",
        2,
        "--view",
        "--view-wait",
        "--log",
        log,
    )
    browser.get(run.url)
    wait_for(browser, "return document.getElementById('result').dataset.result", "the result")
    records = read_log(log)
    assert sum(r["event"] == "tree" and bool(r["replaces"]) for r in records) >= 1
    assert any(r["event"] == "fault" for r in records)
    nodes, rows = check_page(browser, records)
    median, worst, n = check_live(browser, records, rows)
    report_latency(record_property, "symbolic", median, worst, n)
    assert median <= LIVE_MS, (median, worst)
    code, out, err = run.stop(after="the run is over")
    assert code == 0 and out.rstrip().splitlines()[-1].startswith("verified:"), err
    assert "the run is over; the page stays at" in err and "Traceback" not in err


def test_a_pybullet_run_with_slips_live_in_the_browser(browser, tmp_path, record_property):
    plan = plan_file(tmp_path, DOMESTIC, ROOT / "problems" / "bring_object.jshop")
    log = tmp_path / "run.jsonl"
    run = Served(
        "run", plan, "--sim", "--faults", "slip=0.3", "--view", "--view-wait", "--log", log
    )
    browser.get(run.url)
    samples = []  # while the run goes: verified actions, running rows visible
    while not browser.execute_script("return document.getElementById('result').dataset.result"):
        samples.append(
            browser.execute_script("""
            const rows = [...document.querySelectorAll('#tree .node[data-kind=action]')];
            const phase = document.getElementById('a-phase').dataset.phase;
            return [rows.filter(r => r.dataset.status === 'verified').length,
                    !["execute", "monitor"].includes(phase) ||
                      rows.some(r => ["running", "finished"].includes(r.dataset.status)),
                    Number(document.getElementById('camera').dataset.frames)];""")
        )
        assert len(samples) < 4000, "the run did not end"
        time.sleep(0.1)
    records = read_log(log)
    assert any(r["event"] == "fault" and r["kind"] == "slip" for r in records)
    nodes, rows = check_page(browser, records)
    median, worst, n = check_live(browser, records, rows)
    report_latency(record_property, "pybullet", median, worst, n)
    assert median <= LIVE_MS, (median, worst)
    assert len({v for v, _, _ in samples}) >= 2  # the page changed while the run went
    assert all(visible for _, visible, _ in samples)  # the running action always in view
    frames = int(browser.find_element("id", "camera").get_attribute("data-frames"))
    seconds = records[-1]["t"] - next(r["t"] for r in records if r["event"] == "start")
    print(f"camera: {frames} frames in {seconds:.1f} s of run")
    record_property("camera_frames", frames)
    assert frames >= 2 and browser.find_element("id", "camera").get_attribute("src").startswith(
        "blob:"
    )
    code, out, err = run.stop(after="the run is over")
    assert code == (0 if records[-1]["result"] == "verified" else 1), err
    assert "Traceback" not in err


@needs_corpus
def test_htn_view_scrubs_back_to_an_event_and_shows_the_tree_as_it_was(browser, tmp_path):
    plan = plan_file(tmp_path, BLOCKS / "blocks", BLOCKS / "smallproblem")
    log = tmp_path / "run.jsonl"
    r = run_htn(
        "run",
        plan,
        "--robot",
        "symbolic",
        "--faults",
        "effect=0.3",
        "--replan",
        "--seed",
        2,
        "--log",
        log,
    )
    assert r.returncode == 0, r.stderr
    records = read_log(log)
    view = Served("view", log)
    browser.get(view.url)
    check_page(browser, records)
    click = lambda button: browser.find_element("id", button).click()  # noqa: E731

    def at(k):
        wait_for(
            browser,
            f"return document.getElementById('sc-pos').textContent"
            f".startsWith('event {k} of {len(records) - 1}')",
            f"event {k}",
        )
        click("expand-all")
        shown = {i: n["status"] for i, n in page_nodes(browser).items() if n["kind"] == "action"}
        assert shown == expected_statuses(records[: k + 1]), k
        current = browser.find_elements("css selector", "#timeline .ev.current")
        assert [int(c.get_attribute("data-seq")) for c in current] == [k]
        return page_nodes(browser)

    repair = next(k for k, r in enumerate(records) if r["event"] == "replanned")
    k = repair - 1  # the abort, before the repair
    back = len(records) - 1 - k
    for _ in range(back):
        click("sc-back")
    nodes = at(k)
    assert not any(n["grafted"] or n["replaced"] for n in nodes.values())
    assert nodes[records[k]["node"]]["status"] == "aborted"
    future = browser.find_elements("css selector", "#timeline .ev.future")
    assert len(future) == back
    click("sc-forward")
    click("sc-forward")  # the replanned event, then its tree
    nodes = at(k + 2)
    assert any(n["grafted"] for n in nodes.values()) and any(n["replaced"] for n in nodes.values())
    click("sc-first")
    assert at(0) == {}  # the header: no tree yet
    click("sc-forward")
    assert {n["status"] for n in at(1).values() if n["kind"] == "action"} == {"pending"}
    click("sc-fault")
    fault = next(k for k, r in enumerate(records) if r["event"] == "fault")
    nodes = at(fault)
    assert nodes[records[fault]["node"]]["faults"] == 1
    browser.find_element("css selector", "#sc-speed option[value='128']").click()
    click("sc-play")  # plays to the end, and stops
    at(len(records) - 1)
    assert browser.find_element("id", "sc-play").text == "▶"
    code, _, err = view.stop()
    assert code == 0 and "Traceback" not in err


@needs_corpus
def test_a_tree_of_thousands_of_nodes_renders_within_two_seconds(
    browser, tmp_path, record_property
):
    plan = plan_file(tmp_path, BLOCKS_BIG / "blocks", BLOCKS_BIG / "problem")
    log = tmp_path / "run.jsonl"
    r = run_htn("run", plan, "--robot", "symbolic", "-q", "--log", log)
    assert r.returncode == 0, r.stderr
    records = read_log(log)
    size = len(tree_nodes(records))
    assert size >= 1000
    view = Served("view", log)
    browser.get(view.url)  # once to start the page's renderer, then timed afresh
    wait_for(
        browser, f"return window.__treeSizes.some(([n, t, p]) => n >= {size} && p)", "the tree"
    )
    browser.get(view.url)
    painted = wait_for(
        browser,
        f"""return (window.__treeSizes.find(
        ([n, t, p]) => n >= {size} && p) || [])[1]""",
        "the whole tree",
        timeout=60,
    )
    print(
        f"\na tree of {size} nodes ({len(records)} events) painted {painted:.0f} ms "
        f"after the page was opened (in a browser already running)"
    )
    record_property("big_tree_nodes", size)
    record_property("big_tree_painted_ms", round(painted))
    assert painted <= 5 * 2000  # see LIVE_MS: 2 s is the target, measured quiet
    nodes = page_nodes(browser)
    last = next(r["node"] for r in reversed(records) if r.get("node") is not None)
    assert last in nodes  # the running path is open
    assert len(nodes) < size  # and much of the rest is not
    # collapse and expand subtrees
    browser.find_element("id", "expand-all").click()
    nodes = page_nodes(browser)
    assert len(nodes) == size
    order = sorted(nodes.values(), key=lambda n: n["index"])
    for top in (n for n in order if n["depth"] == 1 and n["kind"] == "task"):
        end = next((n["index"] for n in order[top["index"] + 1 :] if n["depth"] <= 1), len(order))
        subtree = {n["id"] for n in order[top["index"] + 1 : end]}
        toggle = f"document.querySelector('.node[data-node=\"{top['id']}\"] .tg').click()"
        browser.execute_script(toggle)
        assert not subtree & set(page_nodes(browser)), top
        browser.execute_script(toggle)
        assert subtree <= set(page_nodes(browser)), top
    view.stop()


def test_a_kitchen_run_in_the_browser_with_its_camera(browser, tmp_path):
    """The README's picture: a kitchen run on the PyBullet robot, past its
    half (seed 3: the cup slips out of the gripper twice, and is grasped again)."""
    plan = plan_file(tmp_path, KITCHEN, ROOT / "problems" / "tray_three.jshop")
    log = tmp_path / "run.jsonl"
    run = Served(
        "run",
        plan,
        "--sim",
        "--faults",
        "slip=0.3",
        "--seed",
        3,
        "--replan",
        "--view",
        "--view-wait",
        "--log",
        log,
    )
    browser.get(run.url)
    shot = os.environ.get("HTN_VIEW_SCREENSHOT") or str(tmp_path / "kitchen.png")
    wait_for(
        browser,
        """const rows = [...document.querySelectorAll('#tree .node[data-kind=action]')];
        return rows.filter(r => r.dataset.status === 'verified').length * 2 >= rows.length
               && Number(document.getElementById('camera').dataset.frames) >= 2
               && document.querySelector('#tree .badge.fault')
               && rows.some(r => r.dataset.status === 'running')""",
        "half of the run, a fault",
    )
    time.sleep(0.3)  # the latest frame drawn
    browser.save_screenshot(shot)
    assert os.path.getsize(shot) > 50_000
    wait_for(browser, "return document.getElementById('result').dataset.result", "the result")
    check_page(browser, read_log(log))
    code, _, err = run.stop(after="the run is over")
    assert code == 0, err
