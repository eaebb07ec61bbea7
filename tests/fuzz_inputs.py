"""The inputs of the hostile-user fuzz run (issue 34), as one Hypothesis
strategy, :func:`inputs`: the suite draws a few hundred of them
(:mod:`test_fuzz_inputs`), ``benchmarks/fuzz_long.py`` a hundred thousand.

An input is one command (``plan``, ``stats``, ``transform``, ``validate``
or ``run --robot symbolic``) on files and options of one of these kinds:

* **hddl slip**: a correct HDDL domain and problem (a small one written
  here, or an IPC 2020 domain with its smallest instance, or an IPC
  partial-order one) with one to three slips a modeller makes: an atom,
  task or subtask with an argument more or less, a parameter declared twice
  (tasks, actions, methods), a cycle or a self-loop in ``:types``, a label
  given twice, an ordering that names no label or runs in a circle, a
  method that decomposes an action;
* **hddl mutant** / **jshop2 mutant**: the files with Hypothesis's
  mutations of :mod:`fuzz_mutations` (expressions and words moved, bytes
  that are not UTF-8, deep nesting); ``run`` takes a JSHOP2 mutant as its
  ``--domain`` and ``--problem`` beside the unmutated example's plan file;
* **options**: a correct input and a value drawn for one of the command's
  times, counts or choices: numbers of every kind (NaN, infinities,
  negatives, zero, fractions, huge ones), words, empty text.

:func:`verdict` says what the answer must be: exit code 0, 1 or 2 (130
and 143 only where a signal came: nothing here sends one), no traceback,
and an exit 2 about an input file located at ``file:line:col:`` (or at
the whole file, ``file: ``, where no place in it is to blame); a usage
error of an option is click's ``Error:`` line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from hypothesis import strategies as st

from fuzz_mutations import mutants

ROOT = Path(__file__).resolve().parent.parent

SMALL_DOMAIN = """(define (domain mini)
  (:requirements :hierarchy :typing :negative-preconditions)
  (:types package vehicle - thing place thing - object)
  (:constants depot - place)
  (:predicates (at ?x - thing ?l - place) (road ?a - place ?b - place) (in ?p - package ?v - vehicle))
  (:task deliver :parameters (?p - package ?to - place))
  (:task go :parameters (?v - vehicle ?to - place))
  (:action drive :parameters (?v - vehicle ?a - place ?b - place)
    :precondition (and (at ?v ?a) (road ?a ?b))
    :effect (and (not (at ?v ?a)) (at ?v ?b)))
  (:action load :parameters (?v - vehicle ?l - place ?p - package)
    :precondition (and (at ?v ?l) (at ?p ?l))
    :effect (and (not (at ?p ?l)) (in ?p ?v)))
  (:action unload :parameters (?v - vehicle ?l - place ?p - package)
    :precondition (and (at ?v ?l) (in ?p ?v))
    :effect (and (not (in ?p ?v)) (at ?p ?l)))
  (:action stay :parameters (?v - vehicle ?l - place) :precondition (at ?v ?l) :effect ())
  (:method m-deliver :parameters (?p - package ?v - vehicle ?a - place ?b - place)
    :task (deliver ?p ?b)
    :precondition (at ?p ?a)
    :ordered-subtasks (and (go ?v ?a) (load ?v ?a ?p) (go ?v ?b) (unload ?v ?b ?p)))
  (:method m-here :parameters (?v - vehicle ?l - place) :task (go ?v ?l)
    :subtasks (and (s1 (stay ?v ?l))))
  (:method m-drive :parameters (?v - vehicle ?a - place ?b - place) :task (go ?v ?b)
    :subtasks (and (s1 (drive ?v ?a ?b)) (s2 (stay ?v ?b)))
    :ordering (and (s1 < s2))))
"""
SMALL_PROBLEM = """(define (problem mini-1) (:domain mini)
  (:objects p1 p2 - package truck - vehicle a b - place)
  (:htn :parameters (?x - package) :subtasks (and (t1 (deliver p1 b)) (t2 (deliver ?x a)))
    :ordering (and (t1 < t2)))
  (:init (at p1 a) (at p2 b) (at truck depot) (road depot a) (road a b) (road b a))
  (:goal (and (at p1 b))))
"""

SHARED = Path(__import__("os").environ.get("HTN_SHARED", ROOT.parent / "shared"))


def hddl_cases() -> list[tuple[str, str, str]]:
    """(name, domain text, problem text): the small model, each IPC 2020
    total-order domain with its smallest instance, and the partial-order
    ones with theirs."""
    cases = [("mini", SMALL_DOMAIN, SMALL_PROBLEM)]
    for corpus in ("ipc2020-to", "ipc-po"):
        folder = SHARED / "corpus" / corpus
        if not folder.is_dir():
            continue
        for d in sorted(p for p in folder.iterdir() if (p / "domain.hddl").is_file()):
            problems = sorted(d.glob("p*.hddl"), key=lambda p: p.stat().st_size)
            if problems:
                cases.append(
                    (f"{corpus}/{d.name}", (d / "domain.hddl").read_text(), problems[0].read_text())
                )
    return cases


def jshop2_cases() -> list[tuple[str, str, str]]:
    """(name, domain text, problem text) of the bundled JSHOP2 examples."""
    cases = []
    for problem in sorted((ROOT / "problems").glob("*.jshop")):
        text = problem.read_text()
        name = re.search(r"\(defproblem\s+\S+\s+(\S+)", text).group(1)
        domain = ROOT / "domains" / f"{name}.jshop"
        if domain.is_file():
            cases.append((problem.stem, domain.read_text(), text))
    return cases


HDDL = hddl_cases()
JSHOP2 = jshop2_cases()

# ------------------------------------------------------------------ slips

ATOM = re.compile(r"\((?!:|domain\s|problem\s)([A-Za-z][\w-]*)((?:\s+[?\w-]+)*)\)")
PARAMS = re.compile(r":parameters\s*\(([^()]*)\)")
TYPES = re.compile(r"\(:types\s")
LABELLED = re.compile(r"\((\w[\w-]*)\s+\([A-Za-z]")
ORDER = re.compile(r"\(\s*(<)\s+(\w[\w-]*)\s+(\w[\w-]*)\s*\)|\(\s*(\w[\w-]*)\s+<\s+(\w[\w-]*)\s*\)")
SLIPS = [
    "arity",
    "arity",
    "arity",
    "duplicate parameter",
    "type cycle",
    "label twice",
    "unknown label",
    "ordering cycle",
    "method of an action",
]


@st.composite
def slipped(draw, text: str) -> tuple[str, str]:
    """``text`` with one slip (see the module docstring); (slip, text)."""
    slip = draw(st.sampled_from(SLIPS), label="slip")
    if slip == "arity":
        atoms = list(ATOM.finditer(text))
        if not atoms:
            return slip, text
        m = draw(st.sampled_from(atoms), label="atom")
        args = m.group(2).split()
        if args and draw(st.booleans(), label="drop?"):
            args = args[:-1]
        else:
            args = args + [draw(st.sampled_from(["?zz", *(args[:1] or ["?zz"]), "depot"]))]
        new = f"({m.group(1)}{''.join(' ' + a for a in args)})"
        return slip, text[: m.start()] + new + text[m.end() :]
    if slip == "duplicate parameter":
        lists = [m for m in PARAMS.finditer(text) if "?" in m.group(1)]
        if not lists:
            return slip, text
        m = draw(st.sampled_from(lists), label="parameters")
        first = re.search(r"\?[\w-]+", m.group(1)).group()
        return slip, text[: m.end(1)] + f" {first}" + text[m.end(1) :]
    if slip == "type cycle":
        m = TYPES.search(text)
        kind = draw(st.sampled_from(["two", "three", "self", "new"]), label="cycle")
        names = (
            re.findall(r"(?<=\s)([A-Za-z][\w-]*)(?=\s)", text[m.end() : text.find(")", m.end())])
            if m
            else []
        )
        names = [n for n in names if n != "object"] or ["ta", "tb", "tc"]
        a = draw(st.sampled_from(names), label="type")
        b, c = f"{a}-b", f"{a}-c"
        extra = {
            "two": f"{a} - {b} {b} - {a}",
            "three": f"{b} - {c} {c} - {a} {a} - {b}",
            "self": f"{a} - {a}",
            "new": "ta - tb tb - ta",
        }[kind]
        if m is None:
            at = text.find("(:predicates")
            return slip, text[:at] + f"(:types {extra})\n  " + text[at:] if at >= 0 else text
        return slip, text[: m.end()] + extra + " " + text[m.end() :]
    if slip == "label twice":
        labels = list(LABELLED.finditer(text))
        if len(labels) < 2:
            return slip, text
        i = draw(st.integers(1, len(labels) - 1), label="label")
        m = labels[i]
        return slip, text[: m.start(1)] + labels[i - 1].group(1) + text[m.end(1) :]
    if slip in ("unknown label", "ordering cycle"):
        orders = list(ORDER.finditer(text))
        if not orders:
            return slip, text
        m = draw(st.sampled_from(orders), label="ordering")
        a, b = (m.group(2), m.group(3)) if m.group(1) else (m.group(4), m.group(5))
        new = f"(< {a} nolabel)" if slip == "unknown label" else f"(< {a} {b}) (< {b} {a})"
        return slip, text[: m.start()] + new + text[m.end() :]
    # a method that decomposes an action
    actions = re.findall(r"\(:action\s+([\w-]+)", text)
    tasks = list(re.finditer(r":task\s+\(([\w-]+)", text))
    if not actions or not tasks:
        return slip, text
    m = draw(st.sampled_from(tasks), label="method")
    return slip, text[: m.start(1)] + draw(st.sampled_from(actions)) + text[m.end(1) :]


# ------------------------------------------------------------------ options

NUMBERS = [
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-inf",
    "Infinity",
    "1e400",
    "-1e400",
    "0",
    "-0",
    "-0.0",
    "-1",
    "1",
    "2",
    "0.5",
    "1.5",
    "1e-9",
    "1e3",
    "3",
    "10",
    "65536",
    "-65537",
    "1" + "0" * 30,
    "-" + "1" * 25,
    "9223372036854775808",
    "2147483648",
    "0x10",
    "1_000",
    "",
    " ",
    "ten",
    "½",
    "٣",
    "1e",
    "--",
    "\x7f",
]
OPTIONS = {
    "plan": {
        "-n": NUMBERS,
        "--max-depth": NUMBERS,
        "--max-memory": NUMBERS,
        "--timeout": NUMBERS,
        "--search": ["dfs", "gbfs", "wastar", "auto", "bfs", ""],
        "-f": ["jshop", "json", "text", "ipc", "xml"],
    },
    "stats": {"--repeat": NUMBERS, "--timeout": NUMBERS},
    "transform": {
        "--timeout": NUMBERS,
        "--metric": ["navigation", "actions", "speed", ""],
        "--rules": ["tray", "tray,nosuch", ",", "", "both-hands"],
    },
    "validate": {"--plan-index": NUMBERS, "--timeout": NUMBERS},
    "run": {
        "--seed": NUMBERS,
        "--plan-index": NUMBERS,
        "--timeout": NUMBERS,
        "--retries": [f"say={n}" for n in NUMBERS[:12]] + ["=", "say", "say=1,=2"],
        "--faults": [f"effect={n}" for n in NUMBERS[:12]] + ["effect", "nosuch=0.1"],
    },
}
# what bounds each command in the run (the long run's budget per input)
LIMIT = "0.5"


@dataclass
class Input:
    kind: str  # hddl slip, hddl mutant, jshop2 mutant, options
    command: str
    files: dict = field(default_factory=dict)  # name -> bytes
    options: list = field(default_factory=list)
    detail: str = ""
    case: str = ""  # the example it was made from (its plan file)

    def argv(self, folder: Path, plan_file: Path | None) -> list:
        d, p = folder / self.name("domain"), folder / self.name("problem")
        if self.command == "run":  # the files given by name are this input's
            options = [folder / o if o in self.files else o for o in self.options]
            return ["run", plan_file, "--robot", "symbolic", "-q", *options]
        if self.command == "validate":
            return ["validate", d, p, plan_file, *self.options]
        return [self.command, d, p, *self.options]

    def name(self, which: str) -> str:
        return next(n for n in self.files if n.startswith(which))


def _bounded(options: list) -> list:
    """``--timeout 0.5`` unless the drawn option is the timeout, then the
    other counts at their defaults (no product of two escapes)."""
    return options if "--timeout" in options else [*options, "--timeout", LIMIT]


@st.composite
def inputs(draw) -> Input:
    kind = draw(
        st.sampled_from(["options", "hddl slip", "hddl mutant", "hddl slip", "jshop2 mutant"]),
        label="kind",
    )
    if kind == "options":
        command = draw(st.sampled_from(sorted(OPTIONS)), label="command")
        name, d, p = draw(
            st.sampled_from(JSHOP2 if command == "run" else HDDL[:1] + JSHOP2), label="example"
        )
        option = draw(st.sampled_from(sorted(OPTIONS[command])), label="option")
        value = draw(st.sampled_from(OPTIONS[command][option]), label="value")
        if option == "--timeout" and command == "stats":
            value = value if _seconds(value) is None or _seconds(value) <= 5 else "2"
        ext = "hddl" if name == "mini" else "jshop"
        return Input(
            kind,
            command,
            {f"domain.{ext}": d.encode(), f"problem.{ext}": p.encode()},
            _bounded([option, value]),
            f"{option} {value!r}",
            name,
        )
    command = draw(
        st.sampled_from(["plan", "plan", "plan", "stats", "transform", "validate", "run"]),
        label="command",
    )
    if kind == "jshop2 mutant":
        name, d, p = draw(st.sampled_from(JSHOP2), label="example")
        ext = "jshop"
    else:
        name, d, p = draw(
            st.sampled_from(HDDL if draw(st.integers(0, 2)) else HDDL[:1]), label="example"
        )
        ext = "hddl"
    which = draw(st.sampled_from(["domain", "domain", "problem", "both"]), label="mutate")
    detail = []
    if kind == "hddl slip":
        for _ in range(draw(st.integers(1, 3), label="slips")):
            if which != "problem":
                slip, d = draw(slipped(d))
                detail.append(slip)
            if which != "domain":
                slip, p = draw(slipped(p))
                detail.append(slip)
        files = {f"domain.{ext}": d.encode(), f"problem.{ext}": p.encode()}
    else:
        files = {
            f"domain.{ext}": draw(mutants(d)) if which != "problem" else d.encode(),
            f"problem.{ext}": draw(mutants(p)) if which != "domain" else p.encode(),
        }
    if command == "run" and ext == "hddl":
        command = "plan"  # the symbolic robot runs JSHOP2 plans of its domains
    options = {
        "stats": ["--repeat", "1"],
        "run": ["--domain", f"domain.{ext}", "--problem", f"problem.{ext}"],
    }.get(command, [])
    return Input(kind, command, files, _bounded(options), f"{name}: {', '.join(detail)}", name)


def _seconds(text: str):
    try:
        return float(text)
    except ValueError:
        return None


# ------------------------------------------------------------------ the answer

LOCATED = re.compile(r"^([^\n]+?):\d+(:\d+)?: ")
USAGE = re.compile(r"^Error: ", re.M)


def verdict(code: int, err: str, files: list) -> str | None:
    """What is wrong with an answer (None: nothing). ``files``: the input
    files' paths as the command got them."""
    if code not in (0, 1, 2):
        return f"exit code {code}"
    if "Traceback" in err or "Exception ignored" in err:
        return "a traceback"
    if code != 2:
        return None
    first = err.splitlines()[0] if err else ""
    names = [str(f) for f in files]
    if any(first.startswith(n + ":") for n in names):
        m = LOCATED.match(first)
        if m and m.group(1) in names or any(first.startswith(n + ": ") for n in names):
            return None
        return f"an error about a file without its place: {first[:200]}"
    if USAGE.search(err) or first.startswith("--"):
        return None  # a usage error of an option (click's, or --retries/--faults)
    return f"an exit 2 that names no file and no option: {first[:200]}"
