"""A generated planning task before it becomes PDDL text.

Generators build a :class:`TaskSpec` (objects, initial facts and goal literals, in the
order they should be written) and :meth:`TaskSpec.to_pddl` renders it as a readable
problem file. Keeping the written order in the spec is what makes output byte-identical
from one run to the next.
"""

from __future__ import annotations

from dataclasses import dataclass

from twostep.pddl import Fact


@dataclass(frozen=True)
class TaskSpec:
    """One problem of a domain: objects ``(name, type)``, init facts and goal literals."""

    name: str
    domain: str
    objects: tuple[tuple[str, str], ...]
    init: tuple[Fact, ...]
    goal: tuple[Fact, ...]
    negative_goal: tuple[Fact, ...] = ()
    pddl_domain: str = ""  # the name in ``(:domain ...)`` when it is not ``domain``

    def to_pddl(self) -> str:
        """The problem as PDDL text: objects grouped by type, one fact per line."""
        by_type: dict[str, list[str]] = {}
        for obj, type_name in self.objects:
            by_type.setdefault(type_name, []).append(obj)
        lines = [
            f"(define (problem {self.name})",
            f"  (:domain {self.pddl_domain or self.domain})",
            "  (:objects",
        ]
        lines += [f"    {' '.join(names)} - {type_name}" for type_name, names in by_type.items()]
        lines += ["  )", "  (:init"]
        lines += [f"    {_atom(fact)}" for fact in self.init]
        lines += ["  )", "  (:goal (and"]
        lines += [f"    {_atom(fact)}" for fact in self.goal]
        lines += [f"    (not {_atom(fact)})" for fact in self.negative_goal]
        lines += ["  ))", ")"]
        return "\n".join(lines) + "\n"


def _atom(fact: Fact) -> str:
    return "(" + " ".join(fact) + ")"


def numbered(prefix: str, count: int, type_name: str) -> tuple[tuple[str, str], ...]:
    """Objects ``prefix1 .. prefixN`` of one type."""
    return tuple((f"{prefix}{i}", type_name) for i in range(1, count + 1))
