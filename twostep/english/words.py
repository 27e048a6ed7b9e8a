"""Words: sentences into tokens, and the one normalisation both sides of a match go through.

A token keeps its ``raw`` text (object names are matched on it) and a ``norm`` form that
phrases are matched on. :func:`normalise` rewrites what English says in several ways into
one: the forms of "to be" and modal verbs (``should be``, ``must be``, ``are``, ``has
been`` -> ``be``), ``on top of`` / ``onto`` / ``atop`` -> ``on``, ``inside`` / ``into``
-> ``in``, negation (``isn't``, ``no longer`` -> ``not``), participles that only say how
a thing got where it is (``placed on``, ``stacked on``, ``stored in`` -> ``on``, ``in``),
and a light stemmer (``contains`` / ``contain``, ``tightened`` / ``tight``, ``closed`` /
``close``). A phrase template of the domain and a sentence about it are normalised alike,
so they meet whatever inflection either uses.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

_TOKEN = re.compile(r"[a-z0-9]+(?:[-_][a-z0-9]+)*|'s\b|[,.;:!?()]")
_MARKUP = re.compile(r"[*_`#>]+(?=\W|$)|(?<=\W)[*_`#>]+|^[*_`#>]+")

ARTICLES = frozenset({"the", "a", "an"})
PREPOSITIONS = frozenset(
    {"on", "in", "at", "of", "from", "with", "for", "to", "under", "above", "by", "off"}
)
CONJUNCTIONS = frozenset({"and", ",", ".", ";", ":", "!", "also", "while", "plus", "then"})
# Words that only say how an object came to be where it is ("b1 is stacked on b2").
_HOW_PLACED = frozenset(
    {
        "placed", "put", "moved", "stacked", "set", "located", "kept", "positioned",
        "sitting", "lying", "resting", "standing", "stored", "stowed", "returned",
        "brought", "back", "mounted", "fitted", "installed",
    }
)  # fmt: skip
_MODALS = frozenset({"should", "must", "will", "shall", "would", "can", "could", "may"})
_BE = frozenset({"is", "are", "was", "were", "be", "been", "being", "am"})
_LEMMAS = {
    "has": "have",
    "had": "have",
    "having": "have",
    "holds": "hold",
    "held": "hold",
    "holding": "hold",
    "carries": "carry",
    "carried": "carry",
    "carrying": "carry",
    "contains": "contain",
    "contained": "contain",
    "containing": "contain",
    "taken": "take",
    "took": "take",
    "takes": "take",
    "removed": "remove",
    "removes": "remove",
    "does": "do",
    "did": "do",
    "done": "do",
}
_REWRITES: tuple[tuple[tuple[str, ...], tuple[str, ...]], ...] = (
    (("on", "the", "top", "of"), ("on",)),
    (("on", "top", "of"), ("on",)),
    (("atop",), ("on",)),
    (("onto",), ("on",)),
    (("upon",), ("on",)),
    (("inside", "of"), ("in",)),
    (("inside",), ("in",)),
    (("into",), ("in",)),
    (("within",), ("in",)),
    (("no", "longer"), ("not",)),
    (("is", "no", "longer"), ("be", "not")),
    (("has", "been"), ("be",)),
    (("have", "been"), ("be",)),
    (("had", "been"), ("be",)),
    (("has", "to", "be"), ("be",)),
    (("have", "to", "be"), ("be",)),
    (("needs", "to", "be"), ("be",)),
    (("need", "to", "be"), ("be",)),
    (("is", "to", "be"), ("be",)),
    (("are", "to", "be"), ("be",)),
)


@dataclass(frozen=True)
class Token:
    """One word of a sentence (or of a phrase template)."""

    raw: str  # lower case, as written (object names are matched on it)
    norm: str  # what phrases are matched on


def tokens(text: str) -> list[str]:
    """``text`` as lower-case words and punctuation; markup (``**``, backticks) and the
    apostrophe of ``n't`` are read away, a possessive ``'s`` is a token of its own."""
    text = text.replace("\u2019", "'").replace("\u2018", "'").replace("\u201c", '"')
    text = text.replace("\u201d", '"').lower()
    text = re.sub(r"n't\b", " not", text)
    text = _MARKUP.sub(" ", text)
    return _TOKEN.findall(text)


def stem(word: str) -> str:
    """A light stemmer: the same stem for the forms the descriptions and the answers use."""
    if word in _LEMMAS:
        return _LEMMAS[word]
    if word in _BE:
        return "be"
    if not word.isalpha():
        return word
    for suffix, replacement in (
        ("ies", "y"),
        ("ened", ""),
        ("ing", ""),
        ("ed", ""),
        ("es", ""),
        ("s", ""),
        ("e", ""),
    ):
        if word.endswith(suffix) and len(word) - len(suffix) >= 3:
            return word[: -len(suffix)] + replacement
    return word


def normalise(words: Sequence[str]) -> list[Token]:
    """Words as tokens (see the module docstring); rewritten spans keep their raw text."""
    out: list[Token] = []
    i = 0
    while i < len(words):
        for pattern, replacement in _REWRITES:
            if tuple(words[i : i + len(pattern)]) == pattern:
                raw = " ".join(pattern)
                out += [Token(raw, word) for word in replacement]
                i += len(pattern)
                break
        else:
            word = words[i]
            following = words[i + 1] if i + 1 < len(words) else ""
            if word in _MODALS and following:
                i += 1  # "should contain" says what "contains" says
                continue
            if word in ("do", "does", "did") and following == "not":
                i += 1
                continue
            out.append(Token(word, stem(word)))
            i += 1
    return _drop_how_placed(out)


def _drop_how_placed(toks: list[Token]) -> list[Token]:
    """``placed on`` -> ``on``, ``put back in`` -> ``in``: participles after ``be`` that
    lead to a preposition of place."""
    kept: list[Token] = []
    for k, token in enumerate(toks):
        if token.raw in _HOW_PLACED and kept and kept[-1].norm in ("be", "not"):
            rest = [t for t in toks[k + 1 :] if t.raw not in _HOW_PLACED]
            if rest and rest[0].norm in ("on", "in", "at", "under", "above"):
                continue
        kept.append(token)
    return kept


def is_article(token: Token) -> bool:
    return token.raw in ARTICLES


__all__ = [
    "ARTICLES",
    "CONJUNCTIONS",
    "PREPOSITIONS",
    "Token",
    "is_article",
    "normalise",
    "stem",
    "tokens",
]
