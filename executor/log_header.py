"""The header of a run's event log (its first line): what ``htn run
--from-log`` needs to run the same thing again.

It records the plan file, domain, problem and functions file by absolute
path with the SHA-256 of their bytes, so that a later run of the log refuses
one that changed since. A log is data: a functions file it names is never
imported because of it (``--from-log`` asks for ``--functions`` and checks
its SHA-256, :mod:`htn.api.run_inputs`). Every field is checked when the
header is read back, with errors that name the log's first line and the
field (``run.jsonl:1: header field "seed": ...``).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from htn.jshop.language.errors import HtnError

FILES = ("plan", "domain", "problem", "functions")


def file_sha256(path: str | None) -> str | None:
    """The SHA-256 of the bytes of ``path`` (None for no path or no such file)."""
    if not path:
        return None
    try:
        with open(path, "rb") as fh:
            return hashlib.sha256(fh.read()).hexdigest()
    except OSError:
        return None


def run_header(
    plan_file: str | None,
    plan_sha256: str | None,
    plan_index: int,
    domain: str | None,
    problem: str | None,
    functions: str | None,
    robot: str,
    seed: int,
    faults: str | None,
    retries: Mapping[str, int],
    replan: bool,
    argv: Sequence[str] | None,
    digests: Mapping[str, str | None],
) -> dict[str, Any]:
    """What a log's header records: enough to run the same thing again
    (``argv``: the command line as given, None for a program's call), with
    the SHA-256 of the plan file, domain, problem and functions file: of the
    bytes the run read and parsed (``digests``: kind -> SHA-256; no file is
    read again here), and the versions it ran with."""
    import platform
    from importlib.metadata import PackageNotFoundError, version

    from htn.installation import version as htn_version

    def installed(name: str) -> str | None:
        try:
            return version(name)
        except PackageNotFoundError:
            return None

    def absolute(p: str | None) -> str | None:
        return os.path.abspath(p) if p else None

    return {
        "htn": htn_version(),
        "argv": None if argv is None else list(argv),
        "plan": absolute(plan_file),
        "plan_sha256": plan_sha256,
        "plan_index": plan_index,
        "domain": absolute(domain),
        "domain_sha256": digests.get("domain") if domain else None,
        "problem": absolute(problem),
        "problem_sha256": digests.get("problem") if problem else None,
        "functions": absolute(functions),
        "functions_sha256": digests.get("functions") if functions else None,
        "robot": robot,
        "seed": seed,
        "faults": faults,
        "retries": dict(sorted(retries.items())),
        "replan": replan,
        "python": platform.python_version(),
        "pybullet": installed("pybullet"),
    }


HEADER_KEYS = (
    "plan",
    "plan_index",
    "domain",
    "problem",
    "robot",
    "seed",
    "faults",
    "retries",
    "replan",
)
MAX_SEED = 2**63
MAX_TEXT = 100_000  # characters of a path or a faults text


def _shown(value: object) -> str:
    text = json.dumps(value)
    return text if len(text) <= 60 else text[:57] + "..."


def read_header(path: str) -> dict[str, Any]:
    """The header event of a log written by ``htn run --log``, each field
    checked (type and range; ``plan_index`` is 1-based)."""
    if not os.path.isfile(path):
        raise HtnError("no such log file", path)
    try:
        with open(path, encoding="utf-8") as fh:
            first = fh.readline(10_000_000)
        rec = json.loads(first)
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise HtnError(f"not a log of htn run --log: {str(exc)[:200]}", path, 1, 1) from exc
    if not isinstance(rec, dict) or rec.get("event") != "header":
        raise HtnError("not a log of htn run --log: its first line is no header event", path, 1, 1)
    missing = [k for k in HEADER_KEYS if k not in rec]
    if missing:
        raise HtnError(f"the header lacks {', '.join(missing)}", path, 1, 1)
    for key, check in CHECKS.items():
        if key in rec:
            why = check(rec[key])
            if why:
                raise HtnError(f'header field "{key}": {why}, got {_shown(rec[key])}', path, 1)
    return rec


FieldCheck = Callable[[Any], str | None]  # a field's value -> what is wrong with it, or None


def _text(optional: bool) -> FieldCheck:
    def check(v: Any) -> str | None:
        if v is None and optional:
            return None
        if not isinstance(v, str) or not v or len(v) > MAX_TEXT or "\0" in v:
            return "expected a path" + (" or null" if optional else "")
        return None

    return check


def _digest(v: Any) -> str | None:
    if v is None:
        return None
    if not isinstance(v, str) or len(v) != 64 or any(c not in "0123456789abcdef" for c in v):
        return "expected a SHA-256 (64 hexadecimal digits) or null"
    return None


def _plan_index(v: Any) -> str | None:
    if type(v) is not int or not 1 <= v <= 10**9:
        return "expected a plan number, 1 or more (the first plan is 1)"
    return None


def _seed(v: Any) -> str | None:
    if type(v) is not int or not -MAX_SEED <= v < MAX_SEED:
        return "expected an integer"
    return None


def _robot(v: Any) -> str | None:
    if not isinstance(v, str) or not v or len(v) > 200:
        return "expected a robot's name"
    return None


def _faults(v: Any) -> str | None:
    if v is None:
        return None
    if not isinstance(v, str) or len(v) > MAX_TEXT:
        return 'expected a faults text ("slip=0.5,nav=0.3") or null'
    return None


def _retries(v: Any) -> str | None:
    if v is None:
        return None
    if not isinstance(v, dict) or not all(
        isinstance(k, str) and k and type(n) is int and 0 <= n <= 10**6 for k, n in v.items()
    ):
        return "expected an object of operator names to retry limits (integers, 0 or more)"
    return None


def _replan(v: Any) -> str | None:
    return None if type(v) is bool else "expected true or false"


CHECKS: dict[str, FieldCheck] = {
    "plan": _text(True),
    "plan_sha256": _digest,
    "plan_index": _plan_index,
    "domain": _text(True),
    "domain_sha256": _digest,
    "problem": _text(True),
    "problem_sha256": _digest,
    "functions": _text(True),
    "functions_sha256": _digest,
    "robot": _robot,
    "seed": _seed,
    "faults": _faults,
    "retries": _retries,
    "replan": _replan,
}


def check_plan_present(plan_file: str | None, log_path: str) -> None:
    """The plan file a header names is there; otherwise an input error at the
    log's first line."""
    if not plan_file:
        raise HtnError(
            "the log records no plan file (its run was of a plan a program passed in)",
            log_path,
            1,
            1,
        )
    if not os.path.isfile(plan_file):
        raise HtnError(f"the plan file of this run is missing: {plan_file}", log_path, 1, 1)


def check_plan_digest(plan_file: str, recorded: str | None, actual: str, log_path: str) -> None:
    """The plan file is unchanged since the logged run (when the header has
    its SHA-256): ``actual`` is the digest of the bytes read now."""
    if recorded and actual != recorded:
        raise HtnError(
            f"the plan file {plan_file} has changed since this run (SHA-256 "
            f"{actual[:12]}..., the log says {recorded[:12]}...)",
            log_path,
            1,
            1,
        )


def check_unchanged(rec: Mapping[str, Any], kind: str, log_path: str) -> None:
    """The ``kind`` file ("domain", "problem") the header names is there and,
    when the header has its SHA-256, unchanged since the run."""
    path, recorded = rec.get(kind), rec.get(f"{kind}_sha256")
    if not path or not recorded:
        return
    actual = file_sha256(path)
    if actual is None:
        raise HtnError(f"the {kind} file of this run is missing: {path}", log_path, 1)
    if actual != recorded:
        raise HtnError(
            f"the {kind} file {path} has changed since this run (SHA-256 "
            f"{actual[:12]}..., the log says {recorded[:12]}...)",
            log_path,
            1,
        )
