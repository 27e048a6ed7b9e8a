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
    """One problem of a domain: objects ``(name, type)``, init facts and goal literals.

    In an untyped domain (``typed=False``) an object's type says what kind of object it is
    (the benchmark's sizes count them by it) but the PDDL does not write it: every object
    is of the root type ``object`` there.
    """

    name: str
    domain: str
    objects: tuple[tuple[str, str], ...]
    init: tuple[Fact, ...]
    goal: tuple[Fact, ...]
    negative_goal: tuple[Fact, ...] = ()
    pddl_domain: str = ""  # the name in ``(:domain ...)`` when it is not ``domain``
    typed: bool = True  # False: the domain has no types; objects are written without one

    def pddl_objects(self) -> dict[str, str]:
        """Each object's type as the PDDL reads it (untyped: ``object``)."""
        return {name: type_name if self.typed else "object" for name, type_name in self.objects}

    def to_pddl(self) -> str:
        """The problem as PDDL text: objects grouped by type (untyped: on one line), one
        fact per line."""
        by_type: dict[str, list[str]] = {}
        for obj, type_name in self.objects:
            by_type.setdefault(type_name, []).append(obj)
        lines = [
            f"(define (problem {self.name})",
            f"  (:domain {self.pddl_domain or self.domain})",
            "  (:objects",
        ]
        if self.typed:
            lines += [f"    {' '.join(names)} - {t}" for t, names in by_type.items()]
        else:
            lines.append(f"    {' '.join(name for name, _ in self.objects)}")
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
