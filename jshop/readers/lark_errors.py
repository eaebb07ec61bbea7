"""Lark's syntax errors as :class:`~htn.jshop.language.errors.HtnError` at
file:line:col, in the words of the slip that most likely caused them.

The parser stops where the structure broke, which is not always where the
slip is: a missing ``)`` shows up lines later, at the next ``(:operator``. So
an error is explained by the first of these that applies:

1. an unknown keyword (``:opertor``): the nearest keyword by edit distance,
   among those the grammar expects there first (``did you mean :operator?``);
2. a parenthesis the layout disagrees with (:mod:`htn.jshop.readers.parens`),
   named only if the text parses once it is fixed: ``this '(' is never
   closed`` at the ``(``, or ``one ')' too many`` at the ``)``;
3. the language's own hints (JSHOP2: :mod:`htn.jshop.readers.jshop2_hints`);
4. what the parentheses alone say: a ``)`` that closes nothing, or the
   ``(`` still open when the file ends;
5. the parser's words: the token and what was expected instead.
"""

from __future__ import annotations

import re
from functools import lru_cache

from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken
from lark.lexer import Token

from htn.jshop.language.errors import HtnError

from . import parens
from .source import position

_KEYWORD = re.compile(r":[a-z][a-z0-9\-]*|:-", re.I)


def parse(lark, text: str, file: str, token_names: dict, hints=None, **options):
    """``lark.parse(text)``; a syntax error becomes one ``HtnError`` (see the
    module docstring). ``hints(text, file, error, offset, open_lists)`` may
    return the language's own explanation, or None."""
    try:
        return lark.parse(text, **options)
    except UnexpectedInput as e:
        raise explain(lark, text, file, e, token_names, hints, options) from None


def explain(
    lark, text: str, file: str, e: UnexpectedInput, token_names: dict, hints=None, options=None
) -> HtnError:
    at = _offset(text, e)
    found = _unknown_keyword(lark, text, file, e, at) or _paren_fix(
        lark, text, file, at, options or {}
    )
    if found is None and hints is not None:
        found = hints(text, file, e, at, parens.open_lists(text, at))
    return found or _paren_facts(text, file, e, at) or _parser_words(text, file, e, token_names)


def _offset(text: str, e: UnexpectedInput) -> int:
    """Where the error is: the offending character or token (end of file: its length)."""
    if isinstance(e, UnexpectedCharacters):
        return e.pos_in_stream
    if isinstance(e, UnexpectedToken) and _token(e).type != "$END":
        start = _token(e).start_pos
        if start is not None:
            return start
    return len(text)


def _token(e: UnexpectedToken) -> Token:
    """The token the parser could not take."""
    return e.token  # type: ignore[attr-defined]  # lark sets it in an untyped __init__, undeclared


def at_offset(text: str, file: str, offset: int, message: str) -> HtnError:
    line, col = position(text, offset)
    return HtnError(message, file, line, col)


# ------------------------------------------------------------------ keywords


@lru_cache(maxsize=8)
def _keywords(lark) -> dict[str, set[str]]:
    """Terminal name -> the keywords it spells (``:operator``, ``defdomain``)."""
    out = {}
    for t in lark.terminals:
        value = t.pattern.value
        if t.pattern.type == "str":
            if re.fullmatch(r":?[a-z][a-z\-]*|:-", value, re.I):
                out[t.name] = {value.lower()}
        else:
            found = set(_KEYWORD.findall(re.sub(r"\\(.)", r"\1", value)))
            if found:
                out[t.name] = {k.lower() for k in found}
    return out


def _expected(e: UnexpectedInput) -> set:
    return set(getattr(e, "allowed", None) or getattr(e, "expected", None) or ())


def _unknown_keyword(lark, text: str, file: str, e: UnexpectedInput, at: int):
    """``:opertor`` -> unknown keyword, did you mean ``:operator``? A word
    where only keywords fit (``defdomian``) gets the nearest one too."""
    keywords = _keywords(lark)
    known = set().union(*keywords.values())
    fitting = set().union(*(keywords.get(t, set()) for t in _expected(e)))
    m = re.compile(r":[^\s();]*|[^\s();]+").match(text, at)
    word = m.group() if m else ""
    if word.startswith(":") and word.lower() not in known:
        best = nearest(word.lower(), fitting) or nearest(word.lower(), known)
        more = (
            f"; did you mean {best}?"
            if best
            else (f"; expected {', '.join(sorted(fitting))}" if fitting else "")
        )
        return at_offset(text, file, at, f"unknown keyword '{word}'{more}")
    tok = getattr(e, "token", None)
    if tok is not None and tok.type == "NAME" and "NAME" not in _expected(e):
        words = {k for k in fitting if not k.startswith(":")}
        best = nearest(word.lower(), words)
        if best and best != word.lower():
            return at_offset(text, file, at, f"unknown word '{word}'; did you mean {best}?")
    return None


def nearest(word: str, candidates, most: int | None = None):
    """The candidate nearest to ``word`` by edit distance (Levenshtein), if
    it is near enough (at most a third of the word's letters, and 2 or more)."""
    most = max(2, len(word) // 3) if most is None else most
    scored = sorted((edit_distance(word, c), c) for c in candidates)
    return scored[0][1] if scored and scored[0][0] <= most else None


def edit_distance(a: str, b: str) -> int:
    """Insertions, deletions and substitutions that turn ``a`` into ``b``."""
    row = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        prev, row[0] = row[0], i
        for j, cb in enumerate(b, 1):
            prev, row[j] = row[j], min(row[j] + 1, row[j - 1] + 1, prev + (ca != cb))
    return row[-1]


# ------------------------------------------------------------------ parentheses

TRIES = 3  # fixes tried by parsing the fixed text (each is one more parse)


def _paren_fix(lark, text: str, file: str, at: int, options: dict):
    """The first parenthesis the layout disagrees with (before the end of
    the error's line) whose fix makes the text parse."""
    eol = text.find("\n", at)
    for s in parens.layout_suspects(text, len(text) if eol < 0 else eol, limit=TRIES):
        try:
            lark.parse(s.fixed(text), **options)
        except UnexpectedInput:
            continue
        o = s.opened
        if s.kind == "unclosed":
            end_line = position(text, s.at)[0]
            return HtnError(
                f"this '(' is never closed; a ')' at the end of line {end_line} would close it",
                file,
                o.line,
                o.col,
            )
        return at_offset(
            text,
            file,
            s.at,
            f"one ')' too many: this one closes the '(' at "
            f"{o.line}:{o.col}, but line {s.line} below is laid out inside that list",
        )
    return None


def _paren_facts(text: str, file: str, e: UnexpectedInput, at: int):
    stray = parens.first_unmatched_close(text, at + 1)
    if stray is not None:
        return at_offset(
            text,
            file,
            stray,
            "this ')' closes nothing: every '(' before it is closed already (one ')' too many)",
        )
    if at >= len(text) or (isinstance(e, UnexpectedToken) and _token(e).type == "$END"):
        still = parens.open_lists(text, len(text))
        if still:
            o = still[-1]
            return HtnError(
                "this '(' is never closed: the file ends first (a ')' is "
                "missing in the list it opens)",
                file,
                o.line,
                o.col,
            )
    return None


# ------------------------------------------------------------------ the parser's words


def _parser_words(text: str, file: str, e: UnexpectedInput, token_names: dict) -> HtnError:
    if isinstance(e, UnexpectedCharacters):
        return HtnError(f"unexpected character {text[e.pos_in_stream]!r}", file, e.line, e.column)
    if isinstance(e, UnexpectedToken) and _token(e).type != "$END":
        tok = _token(e)
        return HtnError(
            f"unexpected {str(tok)!r}; expected {describe(e.expected, token_names)}",
            file,
            tok.line,
            tok.column,
        )
    if isinstance(e, (UnexpectedToken, UnexpectedEOF)):
        return _eof(text, file)
    return HtnError(
        f"syntax error: {e}",
        file,
        getattr(e, "line", None),  # pragma: no cover
        getattr(e, "column", None),
    )


def describe(expected, token_names: dict) -> str:
    names = sorted({token_names.get(e, e.lstrip("_").lower().replace("_", "-")) for e in expected})
    if len(names) > 6:
        names = names[:6] + ["..."]
    return ", ".join(names)


def _eof(text: str, file: str) -> HtnError:
    lines = text.splitlines() or [""]
    return HtnError("unexpected end of file (missing ')'?)", file, len(lines), len(lines[-1]) + 1)


def check_lark() -> None:
    """Refuse a ``lark`` module older than 0.12, in one line with the fix.
    lark 1.x is what htn declares; lark-parser 0.12, which ROS 2's wheels
    bring (and pip installs over lark 1.x's files), works as well
    (:mod:`htn.jshop.readers.lark_compat`)."""
    import lark

    version = getattr(lark, "__version__", "0")
    parts = [int(p) if p.isdigit() else 0 for p in version.split(".")[:2]] + [0, 0]
    if (parts[0], parts[1]) < (0, 12):
        raise HtnError(
            f"the installed 'lark' module is version {version}, older than htn "
            "reads with: pip install --force-reinstall --no-deps 'lark>=1.1.9'"
        )
