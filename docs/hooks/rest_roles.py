"""A griffe extension for the API reference (mkdocs.yml): the docstrings'
Sphinx roles (``:func:`plan```, ``:class:`~htn.x.Y```) as Markdown code
spans, since mkdocstrings renders docstrings as Markdown, reST's literal
``double backticks`` as single ones, and a paragraph's closing ``::`` as ``:``."""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:func|mod|class|meth|attr|data|exc|obj):`~?([^`]+)`")
LITERAL = re.compile(r"``([^`]+)``")
BLOCK = re.compile(r"(?<=\S)::$", re.M)  # "text::" before an indented block: "text:"


class RestRoles(griffe.Extension):
    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        docstring = obj.docstring
        if docstring is not None:
            text = LITERAL.sub(r"`\1`", ROLE.sub(r"`\1`", docstring.value))
            docstring.value = BLOCK.sub(":", text)
