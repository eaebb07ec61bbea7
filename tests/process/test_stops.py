"""One command's stops (htn.process): owned by the command, passed down,
nothing installed for a library that does not ask."""

from __future__ import annotations

import signal
import sys

import pytest

import htn
from htn.jshop.language.errors import HtnError, is_stop
from htn.jshop.language.functions import FunctionTable, run_user_code
from htn.process import Stops, command

from conftest import ROOT

DOMAIN = ROOT / "domains" / "domestic.jshop"
PROBLEM = ROOT / "problems" / "bring_object.jshop"
SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGALRM)


def _handlers():
    return {s: signal.getsignal(s) for s in SIGNALS}, sys.unraisablehook


def test_the_api_as_a_library_installs_no_signal_handler():
    before = _handlers()
    plans = list(htn.plan(DOMAIN, PROBLEM, timeout=30))
    result = htn.run(plans[0], robot="symbolic", domain=DOMAIN, problem=PROBLEM)
    assert result.summary.result == "verified"
    assert _handlers() == before


def test_a_command_installs_its_handlers_while_it_runs_and_puts_back_the_callers():
    before = _handlers()
    with command() as stops:
        assert signal.getsignal(signal.SIGINT) not in (before[0][signal.SIGINT],)
        assert sys.unraisablehook is not before[1]
        assert not stops.owned  # a library's command: its process is not ours to end
    assert _handlers() == before


def test_a_stop_a_user_function_swallows_is_raised_again_when_it_returns():
    stops = Stops()

    def swallow():
        try:
            stops.deliver(KeyboardInterrupt())  # as the handler does on Ctrl-C
        except KeyboardInterrupt:
            pass
        return 1

    with pytest.raises(KeyboardInterrupt) as caught:
        run_user_code("function swallow", swallow, guard=stops)
    assert is_stop(caught.value)
    assert stops.running_user_code() is None


def test_a_stop_turned_into_the_user_functions_own_error_is_raised_as_the_stop():
    stops = Stops()

    def convert():
        try:
            stops.deliver(KeyboardInterrupt())
        except KeyboardInterrupt:
            raise ValueError("mine") from None

    with pytest.raises(KeyboardInterrupt):
        run_user_code("function convert", convert, guard=stops)


def test_without_stops_user_code_runs_plainly_and_its_own_interrupt_is_an_input_error():
    def own():
        raise KeyboardInterrupt("the user's own")

    with pytest.raises(HtnError, match="function own raised KeyboardInterrupt"):
        run_user_code("function own", own)


def test_the_guard_names_what_runs_for_the_watchdog():
    stops = Stops()
    seen = []
    run_user_code("function look", lambda: seen.append(stops.running_user_code()), guard=stops)
    assert seen == ["function look"]
    assert stops.running_user_code() is None


def test_two_commands_stops_are_independent(tmp_path):
    a, b = Stops(), Stops()
    funcs = tmp_path / "f.py"
    funcs.write_text("def one():\n    return 1\n")
    table = FunctionTable(a)
    table.load_file(str(funcs))
    with pytest.raises(KeyboardInterrupt):
        a.deliver(KeyboardInterrupt())
    assert a.count == 1 and b.count == 0
    assert b.dropped(0) is None
    # the table runs under a's stops: a stop raised into a before the call is
    # not "dropped" by the function (its token is taken when it starts)
    assert table.lookup("one")(()) == 1.0


def test_a_watched_run_is_halted_not_raised_into_while_it_ticks():
    halted = []

    class Run:
        def halt(self, why=""):
            halted.append(why)
            return True  # a tick is running: the halt takes effect after it

    stops = Stops()
    stops.watch(Run())
    stops.deliver(KeyboardInterrupt("stop now"))  # no raise
    assert halted == ["stop now"]
