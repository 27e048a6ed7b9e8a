"""What the pictures show of a PDDL state: which objects lie in which receptacle, and
which receptacles are open.

The vocabulary covers our kitchen domain (``in ?o ?r``; ``accessible ?r`` of an
``openable ?r``) and AlfWorld's ``alfred.pddl`` (``inReceptacle ?o ?r``, ``opened ?r``).
The executor records a :class:`Scene` at the start and after every interaction that
changes it, so a trace can be drawn without any PDDL semantics.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from twostep.pddl import Fact

CONTENT_PREDICATES = frozenset({"in", "inreceptacle"})  # (pred object receptacle)
OPEN_PREDICATES = frozenset({"accessible", "opened"})  # (pred receptacle)
OPENABLE_PREDICATE = "openable"


@dataclass(frozen=True)
class Scene:
    """Receptacles' contents (sorted) and the open ones among the openable."""

    contents: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    openable: frozenset[str] = frozenset()
    open: frozenset[str] = frozenset()

    def is_open(self, receptacle: str) -> bool | None:
        """True/False for an openable receptacle, None for one that has no door."""
        if receptacle not in self.openable:
            return None
        return receptacle in self.open

    def to_dict(self) -> dict[str, Any]:
        return {
            "contents": {r: list(items) for r, items in sorted(self.contents.items())},
            "openable": sorted(self.openable),
            "open": sorted(self.open),
        }

    @staticmethod
    def from_dict(data: Mapping[str, Any]) -> Scene:
        return Scene(
            {str(r): tuple(items) for r, items in (data.get("contents") or {}).items()},
            frozenset(data.get("openable") or ()),
            frozenset(data.get("open") or ()),
        )


def scene_of(state: Iterable[Fact]) -> Scene:
    """The scene of a state (facts are lower-case tuples)."""
    contents: dict[str, list[str]] = {}
    openable: set[str] = set()
    opened: set[str] = set()
    for fact in state:
        if fact[0] in CONTENT_PREDICATES and len(fact) == 3:
            contents.setdefault(fact[2], []).append(fact[1])
        elif fact[0] == OPENABLE_PREDICATE and len(fact) == 2:
            openable.add(fact[1])
        elif fact[0] in OPEN_PREDICATES and len(fact) == 2:
            opened.add(fact[1])
    return Scene(
        {r: tuple(sorted(items)) for r, items in contents.items()},
        frozenset(openable),
        frozenset(opened & openable),
    )
