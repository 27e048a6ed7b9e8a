"""A griffe extension for the site's API pages (mkdocs.yml, mkdocstrings' ``extensions``):
the docstrings' Sphinx roles (``:func:`name```, ``:class:`~a.b.C```) read as code spans
(``name``, ``C``) in the Markdown that mkdocstrings renders, instead of the role's text."""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:py:)?(?:mod|func|class|meth|attr|data|exc|obj|const|term):`([^`]+)`")


def plain(match: re.Match[str]) -> str:
    """A role's target as Sphinx shows it: ``~a.b.c`` as ``c``, ``title <target>`` as its title."""
    target = match.group(1)
    if target.endswith(">") and " <" in target:
        return f"`{target.split(' <', 1)[0]}`"
    if target.startswith("~"):
        return f"`{target[1:].rsplit('.', 1)[-1]}`"
    return f"`{target}`"


def without_roles(text: str) -> str:
    return ROLE.sub(plain, text)


class SphinxRoles(griffe.Extension):
    """Every object's docstring with its roles as code spans."""

    def on_object(self, *, obj: griffe.Object, loader: griffe.GriffeLoader, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = without_roles(obj.docstring.value)
