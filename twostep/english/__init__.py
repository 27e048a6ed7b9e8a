"""English subgoals into PDDL goals without a model: the rules translator.

The paper's translate step asks the LLM to turn an English subgoal into a PDDL goal.
:func:`translate_english` does it with a grammar instead (:mod:`twostep.english.grammar`):
the phrases are the ones each domain's own describer uses for its predicates
(:mod:`twostep.generators.describe`), the names and nouns are the task's objects
(:mod:`twostep.english.lexicon`). It works on any English subgoal (a model's, an
expert's). What it cannot read, or reads two ways, is a failed :class:`Translation` with
the reason: it never guesses. The goal it gives then goes through the same subgoal checks
as a model's (:mod:`twostep.plans.subgoals`).
"""

from __future__ import annotations

from dataclasses import dataclass

from twostep.english.grammar import Grammar, ReadError, Reading, read_sentence
from twostep.generators.describe import describer_domain
from twostep.pddl import Problem, fact_to_pddl


@dataclass(frozen=True)
class Translation:
    """The PDDL goal of an English subgoal, or why there is none (``reason``)."""

    english: str
    pddl: str | None
    reason: str | None = None
    notes: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        return self.pddl is not None


def goal_text(reading: Reading) -> str:
    """The facts of a reading as a PDDL goal, ``(and ...)``."""
    literals = [fact_to_pddl(f) for f in sorted(reading.positive)]
    literals += [f"(not {fact_to_pddl(f)})" for f in sorted(reading.negative)]
    return "(and " + " ".join(literals) + ")"


def _written_in_pddl(problem: Problem, text: str) -> str | None:
    """The goal, when the "English" subgoal is a PDDL goal of the task already."""
    from twostep.llm.parsing import extract_pddl_goal
    from twostep.plans.subgoals import SubgoalError, parse_subgoal

    if "(" not in text:
        return None
    found = extract_pddl_goal(text)
    if found is None:
        return None
    try:
        return parse_subgoal(found, problem).to_pddl()
    except SubgoalError:
        return None


def translate_english(problem: Problem, english: str, domain: str | None = None) -> Translation:
    """``english`` as a PDDL goal of ``problem``; ``domain`` names the describer whose
    phrases to use (default: the one of the PDDL domain's name, else predicate names)."""
    written = _written_in_pddl(problem, english)
    if written is not None:
        return Translation(english, written, None, ("the subgoal is written in PDDL",))
    grammar = Grammar(problem, describer_domain(problem, domain))
    try:
        reading = read_sentence(grammar, english)
    except ReadError as error:
        return Translation(english, None, str(error))
    return Translation(english, goal_text(reading), None, tuple(reading.notes))


__all__ = ["Grammar", "ReadError", "Translation", "goal_text", "read_sentence", "translate_english"]
