"""``htn evaluate``: the same numbers on one process, a local Dask cluster or
a real one (a scheduler and two workers on 127.0.0.1, one of them killed
mid-evaluation), physics-backed runs, the figures, the statistics' edge
cases, and output options checked before any work."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
import warnings
from contextlib import contextmanager
from pathlib import Path

import pytest

from conftest import ROOT, run_htn, run_htn_process, start_htn, wait_until

PROBLEM = "problems/transport_four.jshop"
RUNS, SEED = "600", "5"  # about a second of projected runs on two workers


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The evaluation in one process (--workers 1): JSON and records."""
    records = tmp_path_factory.mktemp("reference") / "runs.jsonl"
    r = run_htn("evaluate", PROBLEM, "--runs", RUNS, "--seed", SEED, "--json", "--records", records)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout), records.read_text()


def _address(info: Path) -> str | None:
    """The address in a scheduler file, or None while it is not all there."""
    try:
        return json.loads(info.read_text()).get("address")
    except (OSError, ValueError):
        return None


@contextmanager
def dask_cluster(folder: Path, workers: int = 2):
    """A Dask scheduler and ``workers`` workers on 127.0.0.1, each its own
    process (``dask scheduler``, ``dask worker``); yields the scheduler's
    address and the worker processes."""
    info = folder / "scheduler.json"
    procs = []

    def start(*args, log: str):
        procs.append(
            subprocess.Popen(
                [sys.executable, "-m", "dask", *map(str, args)],
                stdout=subprocess.DEVNULL,
                stderr=open(folder / log, "w"),
                cwd=folder,
            )
        )
        return procs[-1]

    try:
        start(
            "scheduler",
            "--host",
            "127.0.0.1",
            "--port",
            "0",
            "--no-dashboard",
            "--scheduler-file",
            info,
            log="scheduler.log",
        )
        # Dask writes the file in place: it can exist and still be empty or
        # half-written, so wait until it parses and names an address
        wait_until(lambda: _address(info), "the scheduler's address file", procs[0])
        address = _address(info)
        nodes = [
            start(
                "worker",
                address,
                "--host",
                "127.0.0.1",
                "--nthreads",
                "1",
                "--no-nanny",
                "--no-dashboard",
                "--name",
                f"w{i}",
                log=f"w{i}.log",
            )
            for i in range(workers)
        ]
        from distributed import Client

        with Client(address, timeout="30s") as client:
            client.wait_for_workers(workers, timeout=60)
        yield address, nodes
    finally:
        # workers first: a worker whose scheduler has gone waits to reconnect
        for group in (procs[1:], procs[:1]):
            for p in group:
                p.terminate()
            for p in group:
                try:
                    p.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()


@pytest.mark.dask
@pytest.mark.slow
def test_a_dask_scheduler_gives_the_numbers_of_one_process(reference, tmp_path):
    records = tmp_path / "runs.jsonl"
    with dask_cluster(tmp_path) as (address, _):
        r = run_htn_process(
            "evaluate",
            PROBLEM,
            "--runs",
            RUNS,
            "--seed",
            SEED,
            "--json",
            "--records",
            records,
            "--scheduler",
            address,
        )
    assert r.returncode == 0, r.stderr
    doc, (ref, ref_records) = json.loads(r.stdout), reference
    assert doc["metrics"] == ref["metrics"] and doc["applied"] == ref["applied"]
    assert (doc["workers"], ref["workers"], doc["robot"]) == (2, 1, "projection")
    assert doc["runs_per_s"] > 0
    assert records.read_text() == ref_records  # run by run, in run order
    assert len(ref_records.splitlines()) == 2 * int(RUNS)


@pytest.mark.dask
@pytest.mark.slow
def test_a_worker_killed_mid_evaluation_is_survived(reference, tmp_path):
    records = tmp_path / "runs.jsonl"
    with dask_cluster(tmp_path) as (address, workers):
        proc = start_htn(
            "evaluate",
            PROBLEM,
            "--runs",
            RUNS,
            "--seed",
            SEED,
            "--json",
            "--records",
            records,
            "--scheduler",
            address,
        )
        # records stream in as batches finish: kill a worker once the first are in
        wait_until(
            lambda: records.is_file() and records.read_text().count("\n"),
            "records streamed before the end",
            proc,
            timeout=120,
            every=0.005,
        )
        workers[1].kill()
        done_when_killed = records.read_text().count("\n")
        still_running = proc.poll() is None
        out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    assert still_running and done_when_killed < 2 * int(RUNS)
    doc, (ref, ref_records) = json.loads(out), reference
    assert doc["metrics"] == ref["metrics"]  # complete, nothing counted twice
    assert records.read_text() == ref_records


@pytest.mark.dask
@pytest.mark.slow
def test_local_workers_give_the_numbers_of_one_process(reference):
    from htn.evaluation.cluster import open_runner
    from htn.evaluation.study import prepare_study, run_study

    study, applied = prepare_study(str(ROOT / "domains" / "kitchen.jshop"), str(ROOT / PROBLEM))
    with open_runner(2) as runner:
        assert runner.workers == 1  # nothing started yet
        # as for a study sure to be worth the workers (start_early): the runs
        # then go to them unmeasured, where after runner.start() alone the
        # first batch's CPU time decides, and on a loaded machine it may say
        # the runs stay here (seen once in a full run beside xdist)
        runner.start_soon()
        runner.start()
        comp = run_study(study, PROBLEM, applied, int(RUNS), int(SEED), runner)
    assert comp.workers == 2
    assert json.loads(json.dumps(comp.metrics())) == reference[0]["metrics"]


def _busy(seconds: float) -> None:
    """Work for ``seconds`` of this thread.s CPU time (a batch of that cost)."""
    end = time.thread_time() + seconds
    while time.thread_time() < end:
        pass


@pytest.mark.dask
@pytest.mark.slow
def test_the_workers_start_for_a_study_that_outlasts_their_start():
    from htn.evaluation.cluster import DaskRunner, InProcess, LocalWorkers, start_seconds
    from htn.evaluation.placement import SWITCH_INTERVAL, place

    batch = 0.3  # CPU seconds a batch of 5 runs takes here
    ran, said, starting = [], [], []

    def run(*task):
        ran.append(task)
        _busy(1.0 if len(ran) == 1 else batch)
        if len(ran) == 1:  # the first batch's 0.3 s made the study worth the workers
            starting.append(sys.getswitchinterval() == pytest.approx(SWITCH_INTERVAL))

    tasks = [("batch", i) for i in range(round(8 * start_seconds(2) / batch))]
    workers = LocalWorkers(2, ("htn.evaluation.runs",))
    try:
        runner, results = place(
            workers, tasks, lambda task: 5, run, lambda _: None, "busy", said.append
        )
        assert isinstance(runner, DaskRunner) and workers.workers == 2
        assert runner.workers == 2  # the scheduler's own count
        # they began to start during the first batch, batches ran here
        # until they were up (how many depends on the machine's load), and
        # they were given every batch not begun here
        assert starting == [True]
        assert ran == tasks[: len(ran)]
        assert len(list(results)) == len(tasks) - len(ran)
    finally:
        workers.close()
    assert said == [] and sys.getswitchinterval() != pytest.approx(SWITCH_INTERVAL)
    # the same study of one batch more than the first stays here, and no
    # worker was started for it
    ran.clear()
    small = LocalWorkers(2, ())
    runner, results = place(
        small,
        tasks[:2],
        lambda task: 5,
        lambda *task: (ran.append(task), _busy(batch)),
        lambda _: None,
        "busy",
        said.append,
    )
    assert isinstance(runner, InProcess) and ran == tasks[:1] and small._client is None
    assert len(list(results)) == 1 and ran == tasks[:2]
    assert said and said[0].startswith("--workers 2: 10 busy runs take about 0.")
    assert said[0].endswith(": running in this process")


@pytest.mark.dask
@pytest.mark.slow
def test_a_study_of_long_runs_starts_its_workers_before_measuring_them():
    from htn.evaluation.cluster import DaskRunner, InProcess, LocalWorkers
    from htn.evaluation.placement import place, start_early

    # 20 runs of 2 plans of at least 0.5 s each: worth 2 workers, known before any run
    workers = LocalWorkers(2, ())
    try:
        start_early(workers, 20, 2, 0.5)
        assert workers.starting
        ran = []
        runner, results = place(
            workers,
            [("task", i) for i in range(4)],
            lambda task: 1,
            lambda *task: ran.append(task) or task,
            lambda _: None,
            "busy",
        )
        assert isinstance(runner, DaskRunner) and runner.workers == 2
        # nothing was measured here: the tasks ran here only until the workers were up
        assert sorted([*ran, *results]) == [("task", i) for i in range(4)]
    finally:
        workers.close()
    # one run of each plan is not worth them, nor is a runner that starts nothing
    few = LocalWorkers(2, ())
    start_early(few, 1, 2, 0.5)
    start_early(InProcess(), 20, 2, 0.5)
    assert not few.starting and few._client is None


def test_the_projection_weighs_the_rest_against_the_start():
    from htn.evaluation.placement import EFFICIENCY, Projection

    small = Projection(runs=200, left=175, per_run=0.01, workers=2, start=2.0, cores=2)
    assert small.here == pytest.approx(1.75) and not small.worth_the_workers()
    assert small.note("projected") == (
        "--workers 2: 200 projected runs take about 2.0 s here, "
        "less than starting 2 workers (about 2.0 s): running "
        "in this process"
    )
    big = Projection(runs=2000, left=1975, per_run=0.01, workers=2, start=2.0, cores=2)
    assert big.on_workers == pytest.approx(2.0 + 19.75 / 2 / EFFICIENCY)
    assert big.worth_the_workers()
    # more work than the start, but not enough to win it back
    near = Projection(runs=5, left=4, per_run=1.0, workers=2, start=2.0, cores=2)
    assert not near.worth_the_workers()
    assert near.note("PyBullet") == (
        "--workers 2: 5 PyBullet runs take about 5.0 s here; about "
        "5.2 s with 2 workers, 2.0 s of it to start them: running "
        "in this process"
    )
    # a machine of one core, or nothing left to run: never
    assert not Projection(2000, 1975, 0.01, 2, 2.0, cores=1).worth_the_workers()
    assert not Projection(runs=1, left=0, per_run=5.0, workers=2, start=0.0).worth_the_workers()
    # more workers than cores run no faster than one per core
    assert Projection(2000, 1975, 0.01, 8, 2.0, cores=2).on_workers == big.on_workers


@pytest.mark.slow
def test_a_study_too_small_for_the_workers_runs_here_and_says_so(tmp_path):
    # 30 projected runs take a fraction of what starting two workers takes
    plots = tmp_path / "plots"
    r = run_htn("evaluate", PROBLEM, "--runs", "30", "--json", "--plot", plots, "--workers", "2")
    one = run_htn("evaluate", PROBLEM, "--runs", "30", "--json")
    assert r.returncode == 0, r.stderr
    assert re.fullmatch(
        r"--workers 2: 30 projected runs take about \d+\.\d s here, less than "
        r"starting 2 workers \(about \d+\.\d s\): running in this process\n",
        r.stderr,
    ), r.stderr
    doc = json.loads(r.stdout)
    assert doc["metrics"] == json.loads(one.stdout)["metrics"] and doc["workers"] == 1
    assert doc["applied"] == ["both-hands", "both-hands"] and doc["runs"] == 30
    for name in ("navigation", "manipulation", "actions", "failures"):
        m = doc["metrics"][name]
        assert {"original", "transformed", "change_pct", "p_value"} <= set(m)
        assert {"mean", "sd"} <= set(m["original"])
    pooled = doc["metrics"]["failures"]["transformed"]
    assert 0 <= pooled["wilson95"][0] <= pooled["rate"] <= pooled["wilson95"][1] <= 1
    files = sorted(Path(p).name for p in doc["plots"])
    assert files == sorted(
        f"transport_four_{fig}.{ext}"
        for fig in ("metrics", "distributions")
        for ext in ("png", "pdf", "svg")
    )
    from PIL import Image

    for fig in ("metrics", "distributions"):
        stem = plots / f"transport_four_{fig}"
        assert round(Image.open(f"{stem}.png").info["dpi"][0]) == 300
        assert (stem.with_suffix(".pdf")).read_bytes().startswith(b"%PDF")
        svg = (stem.with_suffix(".svg")).read_text()
        # one colour per series in every figure, none of matplotlib's default cycle
        assert "#0072b2" in svg and "#d55e00" in svg
        assert "#1f77b4" not in svg and "#ff7f0e" not in svg
        assert "applied: both-hands \u00d72" in svg and svg.count("both-hands") == 1
    metrics_svg = (plots / "transport_four_metrics.svg").read_text()
    assert "SD" in metrics_svg and "Wilson 95% CI" in metrics_svg


@pytest.mark.sim
@pytest.mark.slow
def test_physics_backed_evaluation(tmp_path):
    records = tmp_path / "runs.jsonl"
    r = run_htn(
        "evaluate",
        "problems/tray_three.jshop",
        "--robot",
        "pybullet",
        "--runs",
        "1",
        "--faults",
        "slip=0",
        "--json",
        "--records",
        records,
    )
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert (doc["robot"], doc["workers"], doc["applied"]) == ("pybullet", 1, ["tray"])
    assert doc["results"] == {"original": {"verified": 1}, "transformed": {"verified": 1}}
    m = doc["metrics"]
    # measured in the physics world: the tray saves driving and costs arm motion
    assert 0 < m["navigation"]["transformed"]["mean"] < m["navigation"]["original"]["mean"]
    assert 0 < m["manipulation"]["original"]["mean"] < m["manipulation"]["transformed"]["mean"]
    assert m["actions"]["transformed"]["mean"] > m["actions"]["original"]["mean"]
    # one run: no standard deviation, no test
    assert all(v["p_value"] is None and v["original"]["sd"] is None for v in m.values())
    runs = [json.loads(line) for line in records.read_text().splitlines()]
    assert [(x["run"], x["plan"], x["result"]) for x in runs] == [
        (0, "original", "verified"),
        (0, "transformed", "verified"),
    ]


def test_a_task_of_one_plan_gives_that_plans_records_of_the_whole_run():
    # physics studies send each plan's run as a task of its own: a run of a
    # plan depends on its seed alone, not on the plans run beside it
    from htn.evaluation.runs import run_batch
    from htn.evaluation.study import prepare_study

    study, _ = prepare_study(str(ROOT / "domains" / "kitchen.jshop"), str(ROOT / PROBLEM))
    key, blob = study.pack()
    runs = [(3, 8), (4, 9)]
    whole = run_batch(key, blob, runs)
    assert [(r["run"], r["plan"]) for r in whole] == [
        (3, "original"),
        (3, "transformed"),
        (4, "original"),
        (4, "transformed"),
    ]
    for name in study.plans:
        assert run_batch(key, blob, runs, (name,)) == [r for r in whole if r["plan"] == name]


@pytest.mark.slow
def test_few_runs_print_na_and_leak_no_warning():
    warn_all = {**os.environ, "PYTHONWARNINGS": "always"}
    # a process of its own: PYTHONWARNINGS is read when the interpreter starts
    r = run_htn_process("evaluate", PROBLEM, "--runs", "1", env=warn_all, timeout=120)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert "n/a" in r.stdout and "nan" not in r.stdout
    r = run_htn_process("evaluate", PROBLEM, "--runs", "3", "--json", env=warn_all, timeout=120)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert "NaN" not in r.stdout and json.loads(r.stdout)["runs"] == 3


def test_statistics_edge_cases():
    from htn.evaluation.statistics import applied_rules, format_p, pooled_failures, welch_p

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert welch_p([1.0], [2.0, 3.0]) is None  # fewer than 2 runs
        assert welch_p([20.0] * 3, [16.0] * 3) is None  # no variance
        # physics runs that differ by rounding only: scipy's p would be 1.5e-27
        assert (
            welch_p(
                [6.177372650994691, 6.177372650994689], [2.4829454599947622, 2.4829454599947596]
            )
            is None
        )
        assert 0 < welch_p([1.0, 2.0, 3.0], [2.0, 3.0, 5.0]) < 1
        underflow = welch_p([0.0, 0.1] * 200, [100.0, 100.1] * 200)
    assert underflow == 0.0 and format_p(underflow) == "< 1e-300"
    assert (format_p(None), format_p(5.38e-129), format_p(0.0829)) == ("n/a", "5.4e-129", "0.083")
    none_failed = pooled_failures([{"failed": 0, "actions": 20}] * 3)
    assert none_failed["rate"] == 0 and none_failed["wilson95"][0] == 0 < none_failed["wilson95"][1]
    assert applied_rules(["both-hands", "both-hands"]) == "both-hands \u00d72"
    assert applied_rules(["tray", "container", "both-hands"]) == "tray, container, both-hands"
    assert applied_rules([]) == "none"


@pytest.mark.slow
def test_figures_of_runs_that_differ_by_rounding_only(tmp_path):
    from htn.evaluation.figures import plot
    from htn.evaluation.statistics import Comparison

    def run(navigation, manipulation, result="verified"):
        return {
            "navigation": navigation,
            "manipulation": manipulation,
            "actions": 15,
            "failed": 0,
            "failures": 0.0,
            "result": result,
        }

    # two physics runs without faults: the same distances but for the last bits
    comp = Comparison(
        "tray_three.jshop",
        2,
        ["tray"],
        robot="pybullet",
        original=[run(6.177372650994691, 10.1), run(6.177372650994689, 10.2)],
        transformed=[run(2.4829454599947622, 24.5), run(2.48294545999476, 24.6)],
    )
    files = plot(comp, str(tmp_path))
    assert len(files) == 6 and all(os.path.getsize(f) > 1000 for f in files)
    svg = (tmp_path / "tray_three_metrics.svg").read_text()
    assert "runs verified" not in svg  # said only when a run did not end verified
    # a run a fault stopped counts what it did until then: the title says how many did not
    comp.original[1] = run(3.1, 4.0, "aborted")
    plot(comp, str(tmp_path))
    for figure in ("metrics", "distributions"):
        svg = (tmp_path / f"tray_three_{figure}.svg").read_text()
        assert "runs verified: original 1 of 2, transformed 2 of 2" in svg


def test_output_options_are_checked_before_any_work(tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder\n")
    records, plots = tmp_path / "runs.jsonl", tmp_path / "plots"

    def evaluate(*args, env=None):
        if env:  # Dask reads its configuration from the environment when imported
            return run_htn_process(
                "evaluate", PROBLEM, *args, env={**os.environ, **env}, timeout=120
            )
        return run_htn("evaluate", PROBLEM, *args)

    cases = [
        (("--plot", blocker / "plots", "--records", records), f"{blocker}/plots: --plot"),
        (("--records", tmp_path / "missing" / "runs.jsonl"), "--records: no such folder"),
        (
            ("--plot", plots, "--records", tmp_path),
            f"{tmp_path}: --records: is a folder, not a file",
        ),
        (("--plot", plots, "--scheduler", "127.0.0.1:8786"), "not a Dask scheduler address"),
        (("--scheduler", "tcp://127.0.0.1:99999"), "not a Dask scheduler address"),
        (("--workers", "2", "--scheduler", "tcp://127.0.0.1:8786"), "give one of them"),
        (("--robot", "symbolic"), "cannot be evaluated"),
        (("--faults", "slip=0.5"), "unknown fault 'slip'"),
    ]
    for args, message in cases:
        r = evaluate(*args)
        assert r.returncode == 2, (args, r.stderr)
        assert message in r.stderr and "Traceback" not in r.stderr, (args, r.stderr)
        assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not records.exists()
    assert not plots.exists()  # --plot is made only once every option is checked
    # a scheduler nobody listens on is found before planning, within the connect timeout
    r = evaluate(
        "--scheduler",
        "tcp://127.0.0.1:9",
        "--records",
        records,
        "--plot",
        plots,
        env={"DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "1s"},
    )
    assert r.returncode == 2 and "cannot reach the Dask scheduler" in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert sorted(os.listdir(tmp_path)) == ["a-file"]  # nothing written


def test_the_domain_beside_a_problem_is_found_by_the_name_it_defines(tmp_path):
    """``htn evaluate PROBLEM`` takes the file beside the problem that
    defines the problem's domain, whatever the file is called."""
    problem = tmp_path / "tray_three.jshop"
    problem.write_text((ROOT / "problems" / "tray_three.jshop").read_text())
    text = (ROOT / "domains" / "kitchen.jshop").read_text()
    (tmp_path / "a-note.jshop").write_text("; (defdomain kitchen is only a comment here\n")
    mine = tmp_path / "my-kitchen.jshop"
    mine.write_text(text)
    r = run_htn("evaluate", problem, "--runs", "2", "--json")
    assert r.returncode == 0, r.stderr
    # the copy is the one read: a slip in it is reported in it
    mine.write_text(text.rstrip() + "\n(oops\n")
    r = run_htn("evaluate", problem, "--runs", "2")
    assert r.returncode == 2 and r.stderr.startswith(f"{mine}:"), r.stderr


def test_the_options_are_one_object_or_keywords_and_progress_one_object(tmp_path):
    from htn.api.evaluate import EvaluateOptions, Progress, evaluate

    problem, domain = ROOT / PROBLEM, ROOT / "domains" / "kitchen.jshop"
    # the callbacks of old are no keywords of it: said before any work
    with pytest.raises(TypeError, match="on_batch.*progress: one Progress object"):
        evaluate(problem, runs=2, on_batch=print)
    told = []

    class Told(Progress):
        def started(self, workers, notes):
            told.append(("started", workers, notes))

        def phase(self, text):
            told.append(("phase", text))

        def batch(self, records, runs):
            told.append(("batch", len(records), runs))

    options = EvaluateOptions(runs=3, seed=4, records=tmp_path / "runs.jsonl")
    one = evaluate(problem, options, domain=domain, progress=Told())
    # a keyword given beside the object is used over the object's own
    two = evaluate(problem, options, domain=domain, runs=2)
    assert (one.comparison.runs, two.comparison.runs) == (3, 2)
    assert one.metrics == evaluate(problem, domain=domain, runs=3, seed=4).metrics
    assert told[:2] == [("phase", "reading the problem and its domain"), ("started", 1, [])]
    assert ("phase", "planning") in told and (
        "phase",
        "3 runs of each plan on the projection robot",
    ) in told
    assert sum(t[2] for t in told if t[0] == "batch") == 3
    assert len((tmp_path / "runs.jsonl").read_text().splitlines()) == 2 * 2  # two's runs
