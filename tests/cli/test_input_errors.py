"""Bad input gets one line ``file:line:col: message``, exit code 2, no traceback."""

from __future__ import annotations

import pytest

from conftest import run_htn, start_htn

DOMAIN = """(defdomain d (
  (:operator (!go ?a ?b) ((at ?a)) ((at ?a)) ((at ?b)))
  (:method (travel ?to) ((at ?from)) ((!go ?from ?to)))))
"""
PROBLEM = "(defproblem p d ((at home)) ((travel work)))\n"


def write(tmp_path, domain=DOMAIN, problem=PROBLEM):
    d, p = tmp_path / "d.jshop", tmp_path / "p.jshop"
    d.write_text(domain)
    p.write_text(problem)
    return d, p


def at(file, text: str) -> str:
    """``file:line:col:`` of the first ``text`` in ``file``."""
    source = file.read_text()
    offset = source.index(text)
    line = source.count("\n", 0, offset) + 1
    return f"{file}:{line}:{offset - source.rfind(chr(10), 0, offset)}:"


def check_error(result, prefix, message):
    assert result.returncode == 2, result.stdout + result.stderr
    assert "Traceback" not in result.stderr
    first = result.stderr.splitlines()[0]
    assert first.startswith(prefix), first
    assert message in first, first


def test_the_valid_files_plan(tmp_path):
    d, p = write(tmp_path)
    r = run_htn("plan", d, p, "-f", "jshop")
    assert r.returncode == 0 and "(!go home work)" in r.stdout


def test_missing_closing_parenthesis(tmp_path):
    # the parser only sees the end of the file; the message names the '('
    # left open (issue 19: plain words instead of "unexpected end of file")
    d, p = write(tmp_path, domain=DOMAIN.rstrip()[:-1])
    check_error(run_htn("plan", d, p), f"{d}:1:1:", "this '(' is never closed: the file ends first")


def test_unexpected_token_points_at_it(tmp_path):
    d, p = write(tmp_path, domain=DOMAIN.replace("(!go ?from ?to)", "(!go ?from ?to) )"))
    check_error(run_htn("plan", d, p), f"{d}:3:59:", "this ')' closes nothing")


def test_unexpected_character(tmp_path):
    d, p = write(tmp_path, domain=DOMAIN.replace("?to)))", "?to #)))"))
    check_error(run_htn("plan", d, p), f"{d}:3:54:", "unexpected '#': comments start with ';'")
    d, p = write(tmp_path, domain=DOMAIN.replace("?to)))", "?to %)))"))
    check_error(run_htn("plan", d, p), f"{d}:3:54:", "unexpected character '%'")


def test_unknown_task_in_the_problem(tmp_path):
    d, p = write(tmp_path, problem="(defproblem p d ((at home))\n  ((fly work)))\n")
    r = run_htn("plan", d, p)
    check_error(r, f"{p}:2:5:", "unknown task 'fly'")
    assert "^" in r.stderr  # the source line with a caret


def test_unknown_operator_in_the_problem(tmp_path):
    d, p = write(tmp_path, problem="(defproblem p d () ((!jump)))")
    check_error(run_htn("plan", d, p), f"{p}:1:22:", "unknown primitive task '!jump'")


def test_arity_mismatch_in_the_problem(tmp_path):
    d, p = write(tmp_path, problem="(defproblem p d ((at home)) ((travel work now)))")
    check_error(run_htn("plan", d, p), f"{p}:1:31:", "'travel' takes 1 argument, given 2")


def test_arity_mismatch_in_a_method_body_is_a_warning(tmp_path):
    # legal JSHOP2 (manual 3.7, 5.2.1): that branch simply never applies
    d, p = write(tmp_path, domain=DOMAIN.replace("((!go ?from ?to))", "((!go ?to))"))
    r = run_htn("plan", d, p, "-f", "jshop")
    assert r.returncode == 1 and "Traceback" not in r.stderr  # no plan, no error
    assert (
        f"{d}:3:40: warning: '!go' takes 2 arguments, given 1; branch Method0Branch0 "
        "of travel can never succeed" in r.stderr
    )
    other = DOMAIN.replace("(:method", "(:method (travel ?to) () ((!go ?to)))\n  (:method")
    d, p = write(tmp_path, domain=other)
    r = run_htn("plan", d, p, "-f", "jshop")
    assert r.returncode == 0 and r.stdout.count("(!go home work)") == 1  # the next method
    assert "warning: '!go' takes 2 arguments, given 1" in r.stderr


def test_a_problem_for_another_domain(tmp_path):
    d, p = write(tmp_path, problem="(defproblem p\n    elsewhere ((at home)) ((travel work)))")
    out = tmp_path / "plan.txt"
    out.write_text("previous plan\n")
    good = tmp_path / "good.txt"  # a plan of the domain's own problem
    (tmp_path / "own").mkdir()
    assert run_htn("plan", d, write(tmp_path / "own")[1], "-o", good, "-q").returncode == 0
    for command in (
        ["plan", d, p, "-o", out],
        ["validate", d, p, out],
        ["run", good, "--robot", "symbolic", "--domain", d, "--problem", p],
        ["transform", d, p],
        ["evaluate", p, "--domain", d, "--runs", "2"],
    ):
        r = run_htn(*command)
        check_error(r, f"{p}:2:5:", "problem 'p' is for domain 'elsewhere', but")
        assert "defines 'd'" in r.stderr.splitlines()[0]
    assert out.read_text() == "previous plan\n"


def test_undefined_function(tmp_path):
    d, p = write(tmp_path, domain=DOMAIN.replace("((at ?from))", "((at ?from) (call Far ?from))"))
    check_error(run_htn("plan", d, p), f"{d}:3:", "undefined function 'Far'")


def test_undefined_comparator(tmp_path):
    d, p = write(
        tmp_path, domain=DOMAIN.replace("((at ?from))", "(:sort-by ?from Nearest (at ?from))")
    )
    check_error(run_htn("plan", d, p), f"{d}:3:", "undefined comparator 'Nearest'")


def test_missing_files_and_swapped_files(tmp_path):
    d, p = write(tmp_path)
    check_error(
        run_htn("plan", tmp_path / "no.jshop", p), f"{tmp_path / 'no.jshop'}:", "no such file"
    )
    check_error(
        run_htn("plan", d, tmp_path / "no.jshop"), f"{tmp_path / 'no.jshop'}:", "no such file"
    )
    check_error(run_htn("plan", p, d), f"{p}:1:1:", "expected a (defdomain")
    check_error(
        run_htn("plan", d, p, "--functions", tmp_path / "no.py"),
        f"{tmp_path / 'no.py'}:",
        "not found",
    )


def test_functions_file_with_a_syntax_error(tmp_path):
    d, p = write(tmp_path)
    bad = tmp_path / "fns.py"
    bad.write_text("def f(:\n")
    check_error(run_htn("plan", d, p, "--functions", bad), f"{bad}:1:", "syntax error")


def test_non_ground_initial_state(tmp_path):
    d, p = write(tmp_path, problem="(defproblem p d ((at ?x)) ((travel work)))")
    check_error(run_htn("plan", d, p), f"{p}:1:18:", "must be ground")


@pytest.mark.parametrize(
    "args", [["--plans", "0"], ["--format", "xml"], ["--timeout", "-1"], ["--bogus"]]
)
def test_bad_options(tmp_path, args):
    d, p = write(tmp_path)
    r = run_htn("plan", d, p, *args)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "Error" in r.stderr or "Usage" in r.stderr


def test_warnings_for_likely_domain_bugs(tmp_path):
    domain = """(defdomain d (
  (:operator (!go ?a) () ((at ?b)) ())
  (:method (m) () ((!go x) (!missing)))))"""
    d, p = write(tmp_path, domain=domain, problem="(defproblem p d () ((m)))")
    r = run_htn("plan", d, p, "-f", "jshop")
    assert r.returncode == 1  # no plan: (!missing) can never succeed
    assert f"{d}:2:3: warning: operator !go: variable ?b" in r.stderr
    assert f"{d}:3:29: warning: primitive task '!missing' has no operator" in r.stderr
    quiet = run_htn("plan", d, p, "-f", "jshop", "--quiet")
    assert quiet.stderr == ""


def test_an_add_list_variable_nothing_binds(tmp_path):
    # it would put an unbound variable into the state, where a later
    # precondition matching it used to crash (IndexError); a state holds
    # ground atoms only (manual 5.1.2)
    domain = """(defdomain d ((:operator (!a ?x) ((not (r ?z))) () ((r ?z)))
  (:operator (!b) ((r ?w) (s ?w ?v ?u)) () ())
  (:method (m) () ((!a x) (!b)))))"""
    d, p = write(tmp_path, domain=domain, problem="(defproblem p d () ((m)))")
    check_error(run_htn("plan", d, p), f"{d}:1:53:", "operator !a adds (r ...) with ?z unbound")


def test_a_variable_passed_down_unbound_into_an_add_list(tmp_path):
    # the same, through the head: (m) passes ?x unbound, !p adds it (that used
    # to crash with an IndexError once !q matched the atom)
    domain = """(defdomain d ((:operator (!p ?d ?a) () () ((r ?a)))
  (:operator (!q) ((r ?w) (s ?w)) () ())
  (:method (m) () ((!p x ?x) (!q)))))"""
    d, p = write(tmp_path, domain=domain, problem="(defproblem p d ((s b)) ((m)))")
    check_error(
        run_htn("plan", d, p),
        at(d, "(r ?a)"),
        f"operator !p adds (r ...) with ?a unbound: (!p x ?x) at {d}:3:21 passes it",
    )


def test_output_file_is_not_left_half_written(tmp_path):
    d, p = write(tmp_path)
    out = tmp_path / "plan.txt"
    out.write_text("previous plan\n")
    bad = tmp_path / "bad.jshop"
    bad.write_text("(defproblem p d ((at home)) ((fly)))")
    assert run_htn("plan", d, bad, "-o", out).returncode == 2
    assert out.read_text() == "previous plan\n"  # untouched by a failed run
    assert run_htn("plan", d, p, "-o", out).returncode == 0
    assert out.read_text().splitlines()[1] == f"; domain: {d.name}"
    assert [f.name for f in tmp_path.iterdir() if f.name.startswith(".htn-")] == []


def test_ctrl_c_on_a_streaming_all_keeps_whole_plans(tmp_path):
    import signal

    d, p = write(
        tmp_path,
        domain="""(defdomain d ((:operator (!a) () () ())
      (:method (m) () ((!a))) (:method (m) () ((!a) (m)))))""",
        problem="(defproblem p d () ((m)))",
    )
    out = tmp_path / "plans.txt"
    proc = start_htn("plan", d, p, "--all", "-f", "jshop", "-o", out)
    printed = []
    while printed.count("--------------------\n") < 11:  # eleven whole plans, then Ctrl-C
        printed.append(proc.stdout.readline())
        assert printed[-1], f"htn plan ended early: {proc.stderr.read()}"
    proc.send_signal(signal.SIGINT)
    # not communicate(): it would skip what readline() buffered
    stdout, stderr = "".join(printed) + proc.stdout.read(), proc.stderr.read()
    assert proc.wait(timeout=60) == 130 and "Traceback" not in stderr
    n = stdout.count("Plan cost:")
    assert n > 10 and stdout.endswith("--------------------\n")
    assert stdout.count("--------------------\n") == n
    saved = out.read_text()  # the -o file holds the same whole plans
    assert saved.count("Plan cost:") == n and saved.endswith("--------------------\n")
    assert f"interrupted; {n} plan(s) found" in stderr


def test_an_error_during_search_leaves_the_output_file_untouched(tmp_path):
    d, p = write(
        tmp_path,
        domain="(defdomain d ((:operator (!a) () () () expensive)))",
        problem="(defproblem p d () ((!a)))",
    )
    out = tmp_path / "plan.txt"
    out.write_text("previous plan\n")
    r = run_htn("plan", d, p, "-o", out)
    check_error(r, f"{d}:1:", "cost of !a is expensive, not a number")
    assert out.read_text() == "previous plan\n"
    assert [f.name for f in tmp_path.iterdir() if f.name.startswith(".htn-")] == []


# ------------------------------------------------------------------ issue 10: hardening

FUNCTIONS = """
import time
def fails(x):
    raise ValueError("no " + x)
def leaves(x):
    import sys
    sys.exit(3)
def spins(x):
    while True:
        time.sleep(0.01)
def word(a, b):
    return "less"
def nothing(a, b):
    return None
def mark(x):
    open(__file__ + ".called", "w").close()
    return 1
"""


def functions_file(tmp_path, name="fns.txt"):
    """A functions file whose name does not end in .py (that used to crash)."""
    f = tmp_path / name
    f.write_text(FUNCTIONS)
    return f


def test_generated_code_does_not_follow_input_nesting(tmp_path):
    # 25 conjuncts (IPC Rover p-19) and a list nested 200 deep in an operator atom
    conjuncts = " ".join(f"(p{i} ?x)" for i in range(25))
    deep = "(" * 200 + "leaf" + ")" * 200
    d, p = write(
        tmp_path,
        domain=f"""(defdomain d (
  (:operator (!a ?x) ({conjuncts} (q ?x {deep})) () ())
  (:method (m) () ((!a x)))))""",
        problem="(defproblem p d ("
        + " ".join(f"(p{i} x)" for i in range(25))
        + f" (q x {deep})) ((m)))",
    )
    r = run_htn("plan", d, p, "-f", "jshop")
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[2] == "(!a x)"


def test_ten_thousand_nested_parentheses(tmp_path):
    d, p = write(
        tmp_path,
        problem="(defproblem p d ((at " + "(" * 10_000 + ")" * 10_000 + ")) ((travel work)))",
    )
    r = run_htn("plan", d, p)
    check_error(r, f"{p}:1:1019:", "parentheses nested more than 1000 deep")
    shown, caret = r.stderr.splitlines()[1:3]
    assert len(shown) < 210 and shown.startswith("  ...") and shown.endswith("...")
    assert shown[caret.index("^")] == "("  # the caret still points at the place


@pytest.mark.parametrize("call", ["(call -)", "(call - )", "(call member a)"])
def test_standard_function_without_enough_arguments(tmp_path, call):
    d, p = write(tmp_path, domain=DOMAIN.replace("((at ?from))", f"((at ?from) {call})"))
    check_error(run_htn("plan", d, p), at(d, "(call"), "call ")


def test_runtime_error_of_a_call_names_its_place(tmp_path):
    d, p = write(
        tmp_path, domain=DOMAIN.replace("((at ?from))", "((at ?from)\n   (call < ?from 1))")
    )
    check_error(run_htn("plan", d, p), at(d, "(call <"), "call <: expected a number, got home")


@pytest.mark.parametrize(
    "function,message",
    [
        ("fails", "function fails raised ValueError: no home"),
        ("leaves", "function leaves called sys.exit(3)"),
    ],
)
def test_user_function_that_raises_or_exits(tmp_path, function, message):
    d, p = write(
        tmp_path, domain=DOMAIN.replace("((at ?from))", f"((at ?from) (call {function} ?from))")
    )
    fns = functions_file(tmp_path)
    r = run_htn("plan", d, p, "--functions", fns)
    # at the user's own line that raised, saying where the domain called it
    raising = next(
        n
        for n, line in enumerate(fns.read_text().splitlines(), 1)
        if ("raise" if function == "fails" else "exit") in line
    )
    check_error(r, f"{fns}:{raising}:", message)
    assert f"(called at {at(d, '(call')[:-1]})" in r.stderr.splitlines()[0]


@pytest.mark.parametrize("comparator,shown", [("word", "'less'"), ("nothing", "None")])
def test_comparator_returning_no_number(tmp_path, comparator, shown):
    d, p = write(
        tmp_path,
        domain=DOMAIN.replace("((at ?from))", f"(:sort-by ?from {comparator} (at ?from))"),
        problem="(defproblem p d ((at home) (at work)) ((travel work)))",
    )
    r = run_htn("plan", d, p, "--functions", functions_file(tmp_path))
    check_error(r, at(d, "(:sort-by"), f"comparator {comparator} returned {shown}, not a number")


def test_user_function_running_past_the_timeout(tmp_path):
    d, p = write(tmp_path, domain=DOMAIN.replace("((at ?from))", "((at ?from) (call spins ?from))"))
    out = tmp_path / "plan.txt"
    out.write_text("previous plan\n")
    r = run_htn(
        "plan",
        d,
        p,
        "--functions",
        functions_file(tmp_path),
        "--timeout",
        "1",
        "-o",
        out,
        timeout=60,
    )
    assert r.returncode == 1 and "Traceback" not in r.stderr
    assert "timed out after 1 s; 0 plan(s) found" in r.stderr
    assert out.read_text() == "previous plan\n"  # no plan: the old file stays
    assert [f.name for f in tmp_path.iterdir() if f.name.startswith(".htn-")] == []


def test_encodings(tmp_path):
    d, p = write(tmp_path)
    p.write_bytes(b"\xef\xbb\xbf" + PROBLEM.encode())  # a UTF-8 byte-order mark
    r = run_htn("plan", d, p, "-f", "jshop")
    assert r.returncode == 0 and "(!go home work)" in r.stdout
    plan = tmp_path / "plan.txt"
    plan.write_bytes(b"\xef\xbb\xbf" + r.stdout.encode())  # plan files too
    r = run_htn("validate", d, p, plan)
    assert r.returncode == 0 and "plan 1: valid" in r.stdout, r.stderr
    p.write_bytes(b"(defproblem p d ((at home))\n  ((travel w\xc3\xa9rk \xff)))")
    r = run_htn("plan", d, p)
    check_error(r, f"{p}:2:17:", "not UTF-8 text: byte 0xff")


@pytest.mark.parametrize("option", ["--dot", "-o"])
def test_unwritable_outputs_are_found_before_planning(tmp_path, option):
    d, p = write(tmp_path, domain=DOMAIN.replace("((at ?from))", "((at ?from) (call mark ?from))"))
    fns = functions_file(tmp_path)
    for target, message in [
        (tmp_path / "missing" / "x.out", f"{option}: no such folder {tmp_path / 'missing'}"),
        (tmp_path, "is a directory"),
    ]:  # click's check
        r = run_htn("plan", d, p, "--functions", fns, option, target)
        assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr
        assert not (tmp_path / "fns.txt.called").exists()  # nothing was planned
    r = run_htn("plan", d, p, "--functions", fns, option, tmp_path / "ok.out")
    assert r.returncode == 0 and (tmp_path / "fns.txt.called").exists()


def test_other_commands_check_options_first(tmp_path):
    d, p = write(tmp_path)
    r = run_htn("transform", tmp_path / "no.jshop", p, "--rules", "bogus")
    assert r.returncode == 2 and "unknown rule(s) bogus" in r.stderr  # before the files
    r = run_htn("transform", d, p, "-o", tmp_path / "missing" / "t.txt")
    check_error(
        r, f"{tmp_path / 'missing' / 't.txt'}:", f"-o: no such folder {tmp_path / 'missing'}"
    )
