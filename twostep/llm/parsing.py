"""Reading the LLM's answers: the English subgoal condition and the PDDL subgoal.

* :func:`parse_english_subgoal` takes the final condition out of the generator's answer
  (the text after "final goal condition is:" or a similar phrase; without one, the last
  sentence if it names something of the task) and recognises the answer "none".
* :func:`extract_pddl_goal` finds the goal in the translator's answer, tolerating code
  fences, prose around it, a missing ``(:goal`` wrapper and unbalanced trailing parens.
* :func:`parse_pddl_subgoal` parses it as a goal of the task
  (:func:`twostep.plans.subgoals.parse_subgoal`: unknown predicate, wrong arity, unknown object).

The rules a parsed subgoal must then meet live in :mod:`twostep.plans.subgoals`. Every failure
is a :class:`~twostep.plans.subgoals.SubgoalError` whose message is the reason for a discard.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from twostep.pddl import Goal, Problem
from twostep.plans.subgoals import SubgoalError, parse_subgoal


@dataclass(frozen=True)
class EnglishSubgoal:
    """The generator's answer: ``kind`` is ``"subgoal"`` (``text`` set) or ``"none"``."""

    kind: str
    text: str | None = None
    note: str | None = None  # how the condition was found when it was not plainly marked


_NONE = re.compile(r"^[\s\"'`*_.:>-]*none[\s\"'`*_.!]*$", re.IGNORECASE)
_NONE_LEAD = re.compile(r"^[\s\"'`*_>-]*none[\"'`*_]*\s*[.!:;,\u2013\u2014-]", re.IGNORECASE)
_MARKER = re.compile(
    r"(?:final\s+(?:sub)?goal\s+condition|(?:sub)?goal\s+condition|final\s+condition)"
    r"[^:\n]{0,60}?(?:\bis\b\s*:?|:)",
    re.IGNORECASE,
)
_AGENT_LABEL = re.compile(r"^\s*\**agent\s*\d+\**\s*:\s*", re.IGNORECASE)
_SENTENCE_END = re.compile(r"(?<=[.!?])\s+")
# "agent1 subgoal:", "**agent2 subgoal:**" (the official code's prompt ends with one):
# a label before the answer, and where a later one starts the answer for another helper.
_SUBGOAL_LABEL = re.compile(
    r"[\s*_`]*agent\s*\d+(?:'s)?\s*(?:sub)?goals?[\s*_`]*:[\s*_`]*", re.IGNORECASE
)
_FENCE_MARK = re.compile(r"```[a-zA-Z]*")
# A sentence about what the agent holds things with ("All hands are empty."): part of a
# condition even though it names nothing of the task.
_AGENT_STATE = re.compile(r"\b(?:hands?|arms?|grippers?)\b.*\b(?:empty|free)\b", re.I)


def _clean_condition(text: str) -> str:
    text = text.strip().strip("*_`\"' ")
    text = re.sub(r"\s+", " ", text)
    return text.rstrip(" .;,").strip("*_`\"' ")


def parse_english_subgoal(
    answer: str, helper: int = 1, problem: Problem | None = None
) -> EnglishSubgoal:
    """Find the final goal condition in ``answer`` (for helper ``helper``).

    Raises :class:`SubgoalError` for an empty answer or prose without a condition.
    """
    text = _FENCE_MARK.sub("", answer).strip()
    if not text:
        raise SubgoalError("empty answer from the subgoal generator")
    text = _own_part(text)
    if not text:
        raise SubgoalError("the generator's answer holds only a label")
    if _NONE.match(text) or _NONE.match(_AGENT_LABEL.sub("", text.splitlines()[0])):
        return EnglishSubgoal("none")
    matches = list(_MARKER.finditer(text))
    if matches:
        # Prefer the condition stated for this helper; else the first one given.
        own = [m for m in matches if re.search(rf"agent\s*{helper}\b", _lead_in(text, m), re.I)]
        match = (own or matches)[0]
        rest = text[match.end() :].lstrip(" \t:")
        lines = [line for line in rest.splitlines() if line.strip()]
        condition = _clean_condition(lines[0]) if lines else ""
        if _NONE.match(condition or "x"):
            return EnglishSubgoal("none")
        if condition:
            return EnglishSubgoal("subgoal", condition)
        raise SubgoalError("the generator's answer announces a goal condition but states none")
    if _NONE_LEAD.match(_AGENT_LABEL.sub("", text)):
        return EnglishSubgoal("none")  # "None. No further helper would ..."
    sentences = [s for s in _SENTENCE_END.split(" ".join(text.split())) if s.strip()]
    taken: list[str] = []
    for sentence in reversed(sentences):
        cleaned = _clean_condition(_AGENT_LABEL.sub("", sentence))
        if not cleaned:
            break
        names = problem is None or _mentions_task(cleaned, problem)
        if not names and _AGENT_STATE.search(cleaned) is None:
            break
        taken.insert(0, cleaned)
    if taken and (problem is None or any(_mentions_task(t, problem) for t in taken)):
        which = "sentence" if len(taken) == 1 else f"{len(taken)} sentences"
        return EnglishSubgoal(
            "subgoal",
            ". ".join(taken),
            note=f"no 'final goal condition' phrase: used the last {which}",
        )
    raise SubgoalError("no final goal condition in the generator's answer")


def continuation(answer: str) -> str | None:
    """What an answer goes on to say for another helper after its own subgoal (the text
    from a later "agentK subgoal:" label on), or None."""
    text = _FENCE_MARK.sub("", answer).strip()
    lead = _SUBGOAL_LABEL.match(text)
    if lead:
        text = text[lead.end() :]
    later = _SUBGOAL_LABEL.search(text)
    return text[later.start() :].strip() if later and later.start() > 0 else None


def _own_part(text: str) -> str:
    """The answer without a leading helper label, up to where a label for another helper
    starts (an answer that goes on to the next helpers' subgoals)."""
    lead = _SUBGOAL_LABEL.match(text)
    if lead:
        text = text[lead.end() :]
    later = _SUBGOAL_LABEL.search(text)
    if later and later.start() > 0:
        text = text[: later.start()]
    return text.strip().strip("`").strip()


def _lead_in(text: str, match: re.Match[str]) -> str:
    """The marker with the words before it in its sentence ("Therefore, agent1's ...")."""
    prefix = text[: match.start()]
    cut = max(prefix.rfind("."), prefix.rfind("\n"))
    return text[cut + 1 : match.end()]


def _mentions_task(text: str, problem: Problem) -> bool:
    """Whether ``text`` names an object, a predicate or a type of the task."""
    lowered = text.lower()
    words = set(re.findall(r"[a-z0-9][a-z0-9_\-]*", lowered))
    if words & set(problem.all_objects):
        return True
    spaced = " ".join(re.findall(r"[a-z0-9]+", lowered))
    types = [t for t in problem.domain.types if t != "object"]
    return any(
        re.search(rf"\b{' '.join(re.findall(r'[a-z0-9]+', name))}s?\d*\b", spaced)
        for name in [*problem.domain.predicates, *types]
    )


# ----------------------------------------------------------------------- PDDL

_FENCE = re.compile(r"```[a-zA-Z]*\s*\n?(.*?)```", re.DOTALL)
_GOAL_START = re.compile(r"\(\s*:goal\b", re.IGNORECASE)
_AND_START = re.compile(r"\(\s*and\b", re.IGNORECASE)
_LITERAL_START = re.compile(r"\(\s*[A-Za-z(]")


def _balanced_span(text: str, start: int) -> str:
    """The s-expression(s) from ``start``: stops at the matching ')' or at prose after it.

    A missing closing paren at the end is added; a stray one ends the span.
    """
    depth = 0
    i = start
    end = start
    while i < len(text):
        ch = text[i]
        if ch == ";":  # PDDL comment
            newline = text.find("\n", i)
            i = len(text) if newline < 0 else newline
            continue
        if ch == "(":
            depth += 1
        elif ch == ")":
            if depth == 0:
                break
            depth -= 1
            end = i + 1
            if depth == 0:
                rest = text[i + 1 :]
                nxt = len(rest) - len(rest.lstrip())
                if not rest.lstrip().startswith("("):  # prose or the end follows
                    break
                i += 1 + nxt
                continue
        elif depth == 0 and not ch.isspace():
            break
        i += 1
    if depth > 0:
        return text[start:].rstrip().rstrip("`").rstrip() + ")" * depth
    return text[start:end]


def extract_pddl_goal(answer: str) -> str | None:
    """The PDDL goal in ``answer`` as text (``(:goal ...)``, ``(and ...)`` or literals)."""
    text = answer
    fences = [f for f in _FENCE.findall(answer) if "(" in f]
    if fences:
        text = next((f for f in fences if _GOAL_START.search(f)), fences[0])
    elif "```" in answer:  # an unclosed fence
        text = answer.split("```", 1)[1]
    for pattern in (_GOAL_START, _AND_START, _LITERAL_START):
        match = pattern.search(text)
        if match:
            span = _balanced_span(text, match.start())
            return span.strip() or None
    return None


def parse_pddl_subgoal(answer: str, problem: Problem) -> Goal:
    """The goal in the translator's ``answer``, checked against ``problem``."""
    if not answer.strip():
        raise SubgoalError("empty answer from the translator")
    goal_text = extract_pddl_goal(answer)
    if goal_text is None:
        raise SubgoalError("no PDDL goal in the translator's answer")
    return parse_subgoal(goal_text, problem)


__all__ = [
    "EnglishSubgoal",
    "SubgoalError",
    "continuation",
    "extract_pddl_goal",
    "parse_english_subgoal",
    "parse_pddl_subgoal",
]
