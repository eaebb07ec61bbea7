"""Lark's syntax errors as :class:`~htn.jshop.language.errors.HtnError` at file:line:col."""
from __future__ import annotations

from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from htn.jshop.language.errors import HtnError


def parse(lark, text: str, file: str, token_names: dict, **options):
    """``lark.parse(text)``; a syntax error becomes one ``HtnError`` naming the
    offending token and, in words from ``token_names``, what was expected."""
    try:
        return lark.parse(text, **options)
    except UnexpectedCharacters as e:
        raise HtnError(f"unexpected character {text[e.pos_in_stream]!r}", file, e.line, e.column)
    except UnexpectedToken as e:
        tok = e.token
        if tok.type == "$END":
            raise _eof(text, file)
        raise HtnError(f"unexpected {str(tok)!r}; expected {describe(e.expected, token_names)}",
                       file, tok.line, tok.column)
    except UnexpectedEOF:
        raise _eof(text, file)
    except UnexpectedInput as e:  # pragma: no cover - other lark errors
        raise HtnError(f"syntax error: {e}", file, getattr(e, "line", None),
                       getattr(e, "column", None))


def describe(expected, token_names: dict) -> str:
    names = sorted({token_names.get(e, e.lstrip("_").lower().replace("_", "-"))
                    for e in expected})
    if len(names) > 6:
        names = names[:6] + ["..."]
    return ", ".join(names)


def _eof(text: str, file: str) -> HtnError:
    lines = text.splitlines() or [""]
    return HtnError("unexpected end of file (missing ')'?)", file, len(lines),
                    len(lines[-1]) + 1)
