"""The mapping file: which ROS 2 action serves each robot skill, and which
service or topic answers each check, for ``--robot ros`` (:mod:`htn.ros.robot`).

It lies beside the domain, named after it (``domains/domestic.jshop`` →
``domains/domestic.ros.toml``), and is TOML::

    namespace = "/robot"     # names without a leading / are under it
    observe = "observe"      # htn_interfaces/srv/GetState: what the robot sees ("": nothing)
    pose = "pose"            # geometry_msgs/msg/PoseStamped: where it is; its stamp is its clock
    wait = 5.0               # seconds a skill or check waits for its server before it fails

    [skills.move_base]       # the skill the action machines call (robot.act("move_base", place))
    action = "/navigate_to_pose"
    type = "nav2_msgs/action/NavigateToPose"
    where = "(location $1 ?x ?y ?yaw)"     # a fact of the world model, $1 the skill's argument
    [skills.move_base.goal]  # the goal's fields (dotted paths) and their values
    "pose.header.frame_id" = "map"
    "pose.pose.position.x" = "?x"
    "pose.pose.orientation" = "yaw_degrees(?yaw)"

    [checks.bumper_free]     # a check answered by a topic instead of a service
    topic = "bumper"
    type = "std_msgs/msg/Bool"
    field = "data"
    equals = false

A value is ``$N`` (the skill's N-th argument), ``$*`` (all of them, a list),
``?v`` (bound by ``where``), ``yaw(E)`` or ``yaw_degrees(E)`` (a quaternion
about z from an angle in radians or degrees), or a literal. A skill that is
not listed is the action ``skill/<name>`` of type ``htn_interfaces/action/Skill``
(its goal's ``args`` the skill's arguments), and a check that is not listed
the service ``check/<name>`` of type ``htn_interfaces/srv/Check``: what
``htn ros robot`` serves. Nothing here imports rclpy; errors are
:class:`~htn.jshop.language.errors.HtnError` located in the file.
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NoReturn

from htn.jshop.language.errors import HtnError

SKILL_TYPE = "htn_interfaces/action/Skill"
CHECK_TYPE = "htn_interfaces/srv/Check"
SUFFIX = ".ros.toml"

_TOP = {"namespace", "observe", "pose", "wait", "skills", "checks"}
_SKILL = {"action", "type", "where", "goal"}
_CHECK = {"service", "type", "request", "topic", "field", "equals", "where"}
# a skill's and a check's: the key naming it, its kind of type, the default
# type, the key of its fields, the default name's prefix
_SERVED = {
    "skills": ("action", "action", SKILL_TYPE, "goal", "skill"),
    "checks": ("service", "srv", CHECK_TYPE, "request", "check"),
}
_FUNCTION = re.compile(r"(yaw|yaw_degrees)\((.*)\)\Z")


def beside(domain: str | Path) -> Path | None:
    """The mapping file beside the domain file ``domain``, if there is one."""
    path = Path(domain)
    found = path.with_name(path.name.split(".")[0] + SUFFIX)
    return found if found.is_file() else None


@dataclass
class Call:
    """One skill's action or one check's service or topic, resolved."""

    name: str  # the full ROS name (/robot/skill/grasp)
    type: str  # package/action|srv|msg/Name
    fields: dict = field(default_factory=dict)  # dotted path -> value expression
    where: str = ""
    field_name: str = ""  # a topic check: the field compared
    equals: Any = None  # a topic check: the value that means ok

    @property
    def is_topic(self) -> bool:
        return "/msg/" in self.type

    def values(self, args: tuple, facts: Iterable[tuple]) -> dict:
        """The goal's (or request's) fields for a call with ``args``: each
        expression evaluated, ``?v`` bound by the first fact matching
        ``where`` (a :class:`HtnError` if none does)."""
        args = tuple(str(a) for a in args)
        bound = _bind(self.where, args, facts) if self.where else {}
        return {path: _value(expr, args, bound, self.name) for path, expr in self.fields.items()}


@dataclass
class Mapping:
    """A mapping file read: the calls by skill and check name."""

    file: str = ""
    namespace: str = "/robot"
    observe: str = "observe"
    pose: str = "pose"
    wait: float = 5.0
    skills: dict = field(default_factory=dict)  # name -> Call
    checks: dict = field(default_factory=dict)  # name -> Call

    def full(self, name: str) -> str:
        """``name`` under the namespace unless it is absolute."""
        return name if name.startswith("/") else f"{self.namespace.rstrip('/')}/{name}"

    def skill(self, name: str) -> Call:
        return self.skills.get(name) or Call(self.full(f"skill/{name}"), SKILL_TYPE, {"args": "$*"})

    def check(self, name: str) -> Call:
        return self.checks.get(name) or Call(self.full(f"check/{name}"), CHECK_TYPE, {"args": "$*"})


def default(namespace: str = "/robot") -> Mapping:
    """The mapping of a robot that serves every skill and check under the
    default names (``htn ros robot`` with nothing remapped)."""
    return Mapping(namespace=namespace)


def read(path: str | Path) -> Mapping:
    """Read the mapping file at ``path``; errors located in it."""
    path = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise HtnError(f"cannot read the mapping file: {exc.strerror or exc}", path) from exc
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        message = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        raise HtnError(
            f"not TOML: {message}", path, int(m[1]) if m else None, int(m[2]) if m else None
        ) from exc
    return _mapping(data, path, text)


def _mapping(data: dict, path: str, text: str) -> Mapping:
    def fail(message: str, key: str = "") -> NoReturn:
        raise HtnError(message, path, _line_of(text, key) if key else None)

    for key in data:
        if key not in _TOP:
            fail(f"unknown key '{key}' (known: {', '.join(sorted(_TOP))})", key)
    m = Mapping(file=path)
    for key in ("namespace", "observe", "pose"):
        if key in data:
            if not isinstance(data[key], str):
                fail(f"'{key}' must be a string", key)
            setattr(m, key, data[key])
    if "wait" in data:
        wait = data["wait"]
        if isinstance(wait, bool) or not isinstance(wait, (int, float)) or not (0 < wait <= 3600):
            fail("'wait' must be a number of seconds in (0, 3600]", "wait")
        m.wait = float(wait)
    for kind, known, into in (("skills", _SKILL, m.skills), ("checks", _CHECK, m.checks)):
        table = data.get(kind, {})
        if not isinstance(table, dict):
            fail(f"'{kind}' must be a table of tables", kind)
        for name, spec in table.items():
            where = f"[{kind}.{name}]"
            if not isinstance(spec, dict):
                fail(f"{where} must be a table", name)
            for key in spec:
                if key not in known:
                    fail(f"{where}: unknown key '{key}' (known: {', '.join(sorted(known))})", key)

            def failed(msg: str, where: str = where, name: str = name) -> NoReturn:
                fail(f"{where}: {msg}", name)

            into[name] = _call(kind, name, spec, m, failed)
    return m


def _call(kind: str, name: str, spec: dict, m: Mapping, fail: Callable[[str], NoReturn]) -> Call:
    for key in ("action", "service", "topic", "type", "where", "field"):
        if key in spec and not (isinstance(spec[key], str) and spec[key]):
            fail(f"'{key}' must be a non-empty string")
    typ = spec.get("type")
    if typ is not None and not re.fullmatch(r"\w+/(msg|srv|action)/\w+", typ):
        fail(f"type '{typ}' is not a ROS type name (package/msg|srv|action/Name)")
    where = spec.get("where", "")
    if where:
        _pattern(where, fail)
    if kind == "checks" and "topic" in spec:
        if "service" in spec or "request" in spec:
            fail("a check is a service or a topic, not both")
        if typ is None or "/msg/" not in typ:
            fail("a topic check needs the topic's message type (package/msg/Name)")
        if "field" not in spec or "equals" not in spec:
            fail("a topic check needs 'field' (a dotted path) and 'equals' (the value meaning ok)")
        return Call(m.full(spec["topic"]), typ, {}, where, spec["field"], spec["equals"])
    # a skill is an action, a check a service: their names, types and fields
    served, part, default_type, fields_key, prefix = _SERVED[kind]
    if typ is not None and f"/{part}/" not in typ:
        fail(
            f"type '{typ}' is not "
            + ("an action" if kind == "skills" else "a service (a check is a service or a topic)")
        )
    fields = spec.get(fields_key, {"args": "$*"} if typ in (None, default_type) else {})
    if not isinstance(fields, dict):
        fail(f"'{fields_key}' must be a table of field = value")
    _check_fields(fields, fail)
    return Call(m.full(spec.get(served, f"{prefix}/{name}")), typ or default_type, fields, where)


def _check_fields(fields: dict, fail) -> None:
    for path, expr in fields.items():
        if not re.fullmatch(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*", path):
            fail(f"'{path}' is not a field path (names joined by dots)")
        if isinstance(expr, str):
            inner = _FUNCTION.match(expr)
            if inner and not inner[2].strip():
                fail(f"{inner[1]}() needs an argument")


def _line_of(text: str, key: str) -> int | None:
    """The first line that names ``key`` (a table header or an assignment)."""
    pattern = re.compile(rf'(^|[\s\[."]){re.escape(key)}(["\].\s=]|$)')
    for number, line in enumerate(text.splitlines(), 1):
        if pattern.search(line.split("#", 1)[0]):
            return number
    return None


# --- values --------------------------------------------------------------------------


def _pattern(text: str, fail=None) -> tuple[str, list[str]]:
    tokens = text.strip().removeprefix("(").removesuffix(")").split()
    if not text.strip().startswith("(") or not text.strip().endswith(")") or not tokens:
        message = f"'where' must be one atom, e.g. (location $1 ?x ?y ?yaw): not {text!r}"
        if fail:
            fail(message)
        raise HtnError(message)
    return tokens[0], tokens[1:]


def _bind(where: str, args: tuple, facts: Iterable[tuple]) -> dict:
    pred, terms = _pattern(where)
    wanted = [_arg(t, args, where) if t.startswith("$") else t for t in terms]
    for p, fact_args in facts:
        if p != pred or len(fact_args) != len(wanted):
            continue
        bound: dict = {}
        for want, have in zip(wanted, fact_args):
            if want.startswith("?"):
                if bound.setdefault(want, have) != have:
                    break
            elif str(want) != str(have):
                break
        else:
            return bound
    shown = "(" + " ".join([pred, *wanted]) + ")"
    raise HtnError(f"no fact of the world model matches {shown}")


def _arg(token: str, args: tuple, where: str):
    if token == "$*":
        return list(args)
    try:
        return args[int(token[1:]) - 1]
    except (ValueError, IndexError):
        raise HtnError(f"{where}: {token} is not one of the {len(args)} argument(s)") from None


def _value(expr: Any, args: tuple, bound: dict, where: str) -> Any:
    if not isinstance(expr, str):
        return expr
    if expr.startswith("$"):
        return _arg(expr, args, where)
    if expr.startswith("?"):
        if expr not in bound:
            raise HtnError(f"{where}: {expr} is not bound by the mapping's 'where'")
        return bound[expr]
    m = _FUNCTION.match(expr)
    if m:
        angle = float(_value(m[2].strip(), args, bound, where))
        if m[1] == "yaw_degrees":
            angle = math.radians(angle)
        return {"x": 0.0, "y": 0.0, "z": math.sin(angle / 2), "w": math.cos(angle / 2)}
    return expr


def fill(message: Any, values: dict) -> Any:
    """Set the dotted ``values`` on ``message`` (a ROS message, or any object
    with attributes), each converted to the type the field has now (a
    ``dict`` value sets the sub-fields it names). Returns ``message``."""
    for path, value in values.items():
        *parents, last = path.split(".")
        target = message
        for name in parents:
            target = _field(target, name, path)
        _set(target, last, value, path)
    return message


def _field(target: Any, name: str, path: str) -> Any:
    if not hasattr(target, name):
        raise HtnError(f"{type(target).__name__} has no field '{name}' (in '{path}')")
    return getattr(target, name)


def _set(target: Any, name: str, value: Any, path: str) -> None:
    current = _field(target, name, path)
    if isinstance(value, dict):
        for key, sub in value.items():
            _set(current, key, sub, f"{path}.{key}")
        return
    try:
        if isinstance(current, bool):
            value = value if isinstance(value, bool) else str(value).lower() in ("1", "true")
        elif isinstance(current, (int, float)):
            value = type(current)(float(value)) if isinstance(current, int) else float(value)
        elif isinstance(current, str):
            value = str(value)
        elif isinstance(current, (list, tuple)) or hasattr(current, "tolist"):
            value = [str(v) for v in value] if isinstance(value, (list, tuple)) else [str(value)]
        setattr(target, name, value)
    except (TypeError, ValueError, AssertionError) as exc:
        raise HtnError(f"cannot set '{path}' to {value!r}: {exc}") from exc
