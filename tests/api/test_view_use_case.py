"""The view use cases (:mod:`htn.api.view`): a finished log read and served
as a page with its token, a run's live view started, the warning for an
address other machines reach; no printing, located errors, and the server
(Starlette) imported only when a page is served."""

from __future__ import annotations

import json
import subprocess
import sys
import urllib.error
import urllib.request

import pytest

from htn import missing_modules
from htn.api.view import (
    LogPage,
    ViewLog,
    exposure_warning,
    read_view_log,
    serve_log,
    start_live_view,
)
from htn.jshop.language.errors import HtnError

from conftest import ROOT

needs_view = pytest.mark.skipif(
    bool(missing_modules("view")), reason="needs the view extra: pip install 'htn[view]'"
)
HEADER = {"event": "header", "domain": "d.jshop", "problem": "p.jshop", "robot": "symbolic"}


def _log(tmp_path, *records, tail=""):
    path = tmp_path / "run.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in records) + tail)
    return path


def _status(url: str) -> int:
    try:
        with urllib.request.urlopen(url, timeout=10) as response:
            return response.status
    except urllib.error.HTTPError as exc:
        return exc.code


def test_importing_the_view_use_cases_loads_no_server():
    r = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys, htn.api.view, htn.cli.view_cmd\n"
            "print(sorted(m for m in sys.modules if m.startswith(('htn.view', "
            "'starlette', 'uvicorn'))))",
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "[]"


def test_only_an_address_other_machines_reach_is_warned_of():
    assert exposure_warning("127.0.0.1") is None and exposure_warning("::1") is None
    assert exposure_warning("localhost") is None
    assert exposure_warning("0.0.0.0") == (
        "the view is served on 0.0.0.0, reachable from "
        "other machines: anyone with its URL (the token) "
        "can watch"
    )
    assert "192.168.1.5" in exposure_warning("192.168.1.5")


@needs_view
def test_a_log_is_read_with_its_warning_and_served_with_its_token(tmp_path, capsys):
    path = _log(
        tmp_path, HEADER, {"event": "summary", "result": "verified"}, tail='{"event": "fini'
    )
    log = read_view_log(path)
    assert isinstance(log, ViewLog) and log.events == 2 and log.path == str(path)
    assert "incomplete" in log.warning
    with serve_log(log) as page:
        assert isinstance(page, LogPage) and page.events == 2
        assert page.url.startswith("http://127.0.0.1:") and "?token=" in page.url
        assert _status(page.url) == 200
        assert _status(page.url.split("?")[0]) == 403
    with pytest.raises(OSError):
        urllib.request.urlopen(page.url, timeout=2)
    assert capsys.readouterr() == ("", "")  # nothing printed


@needs_view
def test_serve_log_takes_a_path_too(tmp_path):
    page = serve_log(_log(tmp_path, HEADER), "127.0.0.1", 0)
    try:
        assert page.events == 1 and page.log.warning is None and _status(page.url) == 200
    finally:
        page.close()


@needs_view
def test_bad_logs_and_addresses_are_input_errors(tmp_path):
    with pytest.raises(HtnError, match="no such log file"):
        read_view_log(tmp_path / "missing.jsonl")
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"event": "header"}\n[1, 2]\n')
    with pytest.raises(HtnError) as err:
        serve_log(bad)
    assert (err.value.file, err.value.line) == (str(bad), 2)
    assert "not an event" in err.value.message
    with pytest.raises(HtnError, match="cannot serve the view on no.such.host.invalid"):
        serve_log(_log(tmp_path, HEADER), "no.such.host.invalid")


@needs_view
def test_a_live_view_starts_before_the_run_and_waits_for_a_page():
    view = start_live_view()
    try:
        assert view.url.startswith("http://127.0.0.1:") and "?token=" in view.url
        assert view.wait_for_page(timeout=0.2) is False  # no page yet
        assert _status(view.url) == 200
    finally:
        view.close()


def test_without_the_view_extra_the_error_names_it(monkeypatch):
    import htn.api.extras as extras

    monkeypatch.setattr(extras, "missing_modules", lambda extra: ["starlette"])
    for call in (
        lambda: read_view_log("run.jsonl"),
        lambda: serve_log("run.jsonl"),
        lambda: start_live_view(what="htn run --view"),
    ):
        with pytest.raises(HtnError, match=r"needs the view extra: pip install 'htn\[view\]'"):
            call()


def command_imports_only_the_api(module: str) -> None:
    """The rule of issue 35 for one module of ``cli/``: it imports only
    ``htn.api``, ``htn.process``, the error type (and ``cli/`` itself), and
    none of its functions is over 50 lines."""
    import ast

    from package_graph import imports_of, package_modules

    modules = package_modules()
    path = modules[module]
    allowed = ("htn.api", "htn.process", "htn.cli")
    bad = [
        m
        for m in imports_of(module, path, modules)
        if not m.startswith(allowed) and m != "htn.jshop.language.errors"
    ]
    assert not bad, f"{module} imports {bad}"
    long = [
        f.name
        for f in ast.walk(ast.parse(path.read_text()))
        if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef))
        and f.end_lineno - f.lineno + 1 > 50
    ]
    assert not long, f"{module}: functions over 50 lines: {long}"


def test_htn_view_parses_calls_the_api_and_prints():
    command_imports_only_the_api("htn.cli.view_cmd")
