"""How a sentence can name the objects of a task: the task's lexicon.

Built from the task's objects and the domain's nouns (:data:`twostep.generators.describe.
NOUNS`, the words the describers use: "4 shot glasses (shot1, ..., shot4)"), and from
the task's PDDL types where a domain has no noun table. An object is named by

* its name (``shot4``, ``the-hub1``), also with spaces for ``-`` / ``_``;
* a noun of it and the number in its name (``shot glass 4``, ``shotglass4``,
  ``hub1`` for ``the-hub1``, ``nut1`` for ``nuts1``), or a name and a noun together
  (``left hand``);

and a noun (``the flat tyre``, ``all balls``) names the objects the noun selects.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

from twostep.english.words import normalise, stem, tokens
from twostep.generators.describe import NOUNS, natural_key
from twostep.pddl import Problem

_TRAILING_NUMBER = re.compile(r"(\d+)$")
# Parts of an agent that hold things: said of the agent whatever the domain calls them.
AGENT_PARTS = frozenset({"hand", "arm", "gripper"})


@dataclass(frozen=True)
class Noun:
    """A noun as the lexicon matches it: its words (stemmed) and the objects it names."""

    text: str
    words: tuple[str, ...]
    objects: tuple[str, ...]
    plural: bool


def _stems(text: str) -> tuple[str, ...]:
    return tuple(t.norm for t in normalise(tokens(text)))


def _number(name: str) -> str | None:
    match = _TRAILING_NUMBER.search(name)
    return match.group(1) if match else None


class Lexicon:
    """The names and nouns of one task (see the module docstring)."""

    def __init__(self, problem: Problem, domain: str | None) -> None:
        self.problem = problem
        self._plurals: set[tuple[str, ...]] = set()
        objects = problem.all_objects
        nouns: list[tuple[str, str, list[str]]] = []
        for noun in NOUNS.get(domain or "", ()):
            nouns.append((noun.singular, noun.plural, noun.select(problem)))
        listed = {singular for singular, _, _ in nouns}
        for type_name in sorted(set(problem.domain.types) | set(objects.values())):
            if type_name == "object" or not type_name:
                continue
            text = type_name.replace("-", " ").replace("_", " ")
            if text in listed:
                continue
            members = [o for o, t in objects.items() if problem.domain.is_subtype(t, type_name)]
            if members:
                nouns.append((text, text + "s", sorted(members, key=natural_key)))
        self.nouns: list[Noun] = []
        for singular, plural, members in nouns:
            self.nouns.append(Noun(singular, _stems(singular), tuple(members), False))
            if _stems(plural) != _stems(singular):
                self.nouns.append(Noun(plural, _stems(plural), tuple(members), True))
            self._plurals.add(tuple(tokens(plural)))
        # longest nouns first: "intact tyre" before "tyre"
        self.nouns.sort(key=lambda n: -len(n.words))
        self.names: dict[tuple[str, ...], set[str]] = {}
        for name in objects:
            self._add(tokens(name), name)
            if re.search(r"[-_]", name):
                self._add(tokens(re.sub(r"[-_]", " ", name)), name)
            number = _number(name)
            for singular, plural, members in nouns:
                if name not in members:
                    continue
                words = tokens(singular)
                if number is not None:
                    self._add([*words, number], name)
                    self._add([*words[:-1], words[-1] + number], name)
                    self._add(["".join(words) + number], name)
                    self._add(["-".join([*words, number])], name)
                    self._add([*words, "number", number], name)
                # "block b2", "left hand", "hand left", "left and right hands"
                self._add([*words, *tokens(name)], name)
                self._add([*tokens(name), *words], name)
                self._add([*tokens(name), *tokens(plural)], name)
        self.longest_name = max((len(k) for k in self.names), default=1)

    def _add(self, words: Iterable[str], name: str) -> None:
        key = tuple(words)
        if key:
            self.names.setdefault(key, set()).add(name)

    # ------------------------------------------------------------------ lookups

    def named(self, raw: tuple[str, ...]) -> set[str]:
        """The objects these raw words name exactly (several: the words are ambiguous)."""
        return self.names.get(raw, set())

    def noun_at_end(self, norms: tuple[str, ...]) -> tuple[Noun, int] | None:
        """The longest noun that ``norms`` end with, and where it starts. What an agent
        holds things with is one noun, whichever word says it ("all hands" are the
        grippers of a domain that has grippers)."""
        for noun in self.nouns:
            size = len(noun.words)
            if size <= len(norms) and norms[-size:] == noun.words:
                return noun, len(norms) - size
        if norms and norms[-1] in AGENT_PARTS:
            for noun in self.nouns:
                if len(noun.words) == 1 and noun.words[0] in AGENT_PARTS:
                    return noun, len(norms) - 1
        return None

    def is_plural(self, raw: tuple[str, ...], size: int) -> bool:
        """Whether the last ``size`` raw words are a plural noun ("shot glasses")."""
        return size > 0 and tuple(raw[-size:]) in self._plurals

    def has_noun(self, word: str) -> bool:
        return any(noun.words[-1] == stem(word) for noun in self.nouns)

    def number_of(self, name: str) -> int | None:
        number = _number(name)
        return int(number) if number is not None else None
