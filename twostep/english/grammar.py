"""The grammar of a domain's English: phrase templates from its own descriptions, and a
parser that reads a subgoal sentence into ground facts of a task.

**Templates.** Every predicate is said the way the domain's describer says it
(:data:`twostep.generators.describe.PHRASES`: ``"{0} is on top of {1}"``, its goal form
``"{0} should be on top of {1}"`` and its group form ``"{0} are on the table"``), or, for a
predicate no table phrases, by its name (``on-table`` -> ``"{0} is on table"``). Each
phrase becomes a :class:`Template` of normalised words and argument slots
(:func:`twostep.english.words.normalise`). From each one the grammar also derives

* its negation (``"{0} is not clear"``; a phrase that already says "not" has none);
* for a phrase of place (``"{0} is in {1}"``, ``"... on ..."``, ``"... at ..."``): the
  converse (``"{1} contains {0}"``, ``"{1} has {0}"``) and the removal (``"{0} is removed
  from {1}"``, ``"... taken off / out of ..."``: the fact is false);
* a form that leaves out an argument after a preposition (``"{0} is tight"`` for ``"{0}
  is tight on {1}"``, ``"{1} is free"`` for ``"{1} of {0} is free"``): the argument left
  out is the one object of its type that the task's initial state or goal relates to the
  others (the nut on that hub, the robot of that gripper);
* for what an agent holds things with (``Your arm is empty``, ``Hand {0} is empty``,
  ``{1} of {0} is free``): "empty" and "free" say the same.

A phrase whose subject is the agent itself (``Your arm ...``, ``You are holding ...``,
``The robot ...`` in termes) has an agent slot, which "the arm", "all hands", "both
hands" fill where the domain has no hand objects.

**Sentences.** A sentence is clauses joined by "and", commas and full stops. A clause is a
template whose slots hold noun phrases (:class:`Mention`, from the task's
:class:`~twostep.english.lexicon.Lexicon`), or, after a first clause, a template without
its subject ("b2 is clear *and on the table*"). A noun phrase is a list of names or noun
phrases ("the flat tyres, wrench, jack, and pump"); a noun phrase is a name, or an
optional quantifier or determiner ("all", "both", "the", "a", "its", "robot1's"), an
ordinal ("the first hub"), adjectives the domain's one-word phrases define ("an inflated
intact tyre") and a noun, and an optional relation ("the nuts on hub1").

**Resolution.** A name is its object; "all X" every X; "the X" the one X, or, when there
are several, those for which the clause's fact is in the task's initial state or goal ("the
nuts are tight on hub1": nuts1); "an X" likewise from the goal first (the intact tyre the
goal puts on hub1). An argument must be of the predicate's type; where two predicates read
alike the one whose types fit closest wins (``robot1 is in room1``: at-robby, not at).

A statement about hands or arms in a domain without any agent state (tyreworld's "all
hands are empty") asks for nothing and adds nothing. Anything else that cannot be read,
or reads two ways, is a :class:`ReadError` with the reason: never a guess.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache

from twostep.english.lexicon import AGENT_PARTS, Lexicon
from twostep.english.words import (
    ARTICLES,
    CONJUNCTIONS,
    Token,
    normalise,
    stem,
    tokens,
)
from twostep.generators.describe import PHRASES, Phrase, natural_key
from twostep.pddl import Domain, Fact, Problem

AGENT = "<agent>"
Item = str | int  # a normalised word, an argument slot, or AGENT

_PLACE = ("in", "on", "at")
_OMISSIBLE_AFTER = frozenset({"on", "in", "of", "at", "from", "with", "to", "for"})
_RELATIONS = frozenset({"on", "in", "of", "from", "at", "for", "with", "inside"})
_REMOVALS: tuple[tuple[str, ...], ...] = (
    ("remove", "from"),
    ("take", "off"),
    ("take", "out", "of"),
    ("take", "from"),
    ("out", "of"),
    ("off",),
)
_ORDINALS = {
    w: i
    for i, w in enumerate(
        [
            "first",
            "second",
            "third",
            "fourth",
            "fifth",
            "sixth",
            "seventh",
            "eighth",
            "ninth",
            "tenth",
        ],
        start=1,
    )
}
_NUMBERED_ORDINAL = re.compile(r"^(\d+)(?:st|nd|rd|th)$")
_FILLERS = frozenset(
    {"also", "completely", "fully", "still", "now", "again", "already", "properly", "each",
     "respectively", "both", "too", "entirely", "safely"}
)  # fmt: skip
_LEADS: tuple[tuple[str, ...], ...] = (
    ("in", "the", "end"),
    ("at", "the", "end"),
    ("finally",),
    ("eventually",),
    ("therefore",),
    ("so",),
    ("ensure", "that"),
    ("make", "sure", "that"),
    ("such", "that"),
    ("so", "that"),
)
_AGENT_WORDS = frozenset({"you", "your", "robot", "agent"})
_EMPTY, _FREE = stem("empty"), stem("free")
_ANYTHING, _NOTHING = stem("anything"), stem("nothing")
_IDLE_WORDS = {
    ("be", _EMPTY), ("be", _FREE), ("be", "not", "hold", _ANYTHING), ("hold", _NOTHING)
}  # fmt: skip
RELEASE = "<release>"
_SELF = frozenset({"you", "yourself", "itself", "himself", "herself", "agent"})
_MAX_SPAN = 14


class ReadError(ValueError):
    """A sentence the grammar cannot read into facts (the message says why)."""


@dataclass(frozen=True)
class Template:
    """How a sentence says a fact of ``predicate``: words and argument slots."""

    predicate: str
    items: tuple[Item, ...]
    negative: bool = False
    omitted: tuple[int, ...] = ()
    text: str = ""
    agent_part: bool = False  # about what an agent holds things with

    @property
    def cost(self) -> int:
        return int(self.negative) + len(self.omitted)

    @property
    def idle(self) -> bool:
        """Says that what an agent holds things with holds nothing ("is empty")."""
        words = tuple(i for i in self.items if isinstance(i, str) and i != AGENT)
        return self.agent_part and not self.negative and words in _IDLE_WORDS


# What "all hands are empty" reads as where the domain has no agent state.
_RELEASE_TEMPLATES = tuple(
    Template(RELEASE, (AGENT, "be", *words), text="the agent holds nothing")
    for words in (
        (_EMPTY,),
        (_FREE,),
        ("not", "hold", _ANYTHING),
        ("not", "carry", _ANYTHING),
        ("hold", _NOTHING),
    )
)


@dataclass(frozen=True)
class Mention:
    """A noun phrase and the objects it may name."""

    text: str
    candidates: tuple[str, ...]
    mode: str  # "exact" | "the" | "a" | "all" | "agent" | "release"
    plural: bool = False
    conditions: tuple[str, ...] = ()  # one-place predicates an indefinite phrase asks for
    other: bool = False  # "all other grippers": not those the rest of the sentence names


@dataclass
class Clause:
    """A read clause: its facts (positive or not), and what the reading assumed."""

    facts: list[tuple[bool, Fact]]
    cost: int
    subject: tuple[Mention, ...] | None
    notes: list[str] = field(default_factory=list)
    others: list[tuple[Fact, str]] = field(default_factory=list)  # facts of "other" phrases


@dataclass(frozen=True)
class Failure:
    position: int
    reason: str
    semantic: bool  # a reading that failed on the task (types, ambiguity), not on words

    def better(self, other: Failure | None) -> bool:
        if other is None:
            return True
        return (self.position, self.semantic) > (other.position, other.semantic)


# ----------------------------------------------------------------- templates


def _template_items(text: str, arity: int) -> list[Item]:
    """A phrase's words, normalised, with ``{k}`` as slot k; articles dropped."""
    marked = re.sub(r"\{(\d+)\}", lambda m: f" slotx{m.group(1)} ", text)
    items: list[Item] = []
    for token in normalise(tokens(marked)):
        match = re.fullmatch(r"slotx(\d+)", token.raw)
        if match:
            items.append(int(match.group(1)))
        elif token.raw not in ARTICLES and token.norm not in (".", ","):
            items.append(token.norm)
    return _agent_subject(items, arity)


def _agent_subject(items: list[Item], arity: int) -> list[Item]:
    """``Your arm is empty`` -> ``<agent> be empty``; ``Hand {0} is empty`` -> ``{0} be
    empty`` (the noun before a slot names its type)."""
    lead: list[str] = []
    for item in items:
        if not isinstance(item, str) or item in ("be", "have", "hold", "carry", "not"):
            break
        lead.append(item)
    rest = items[len(lead) :]
    if lead and any(word in _AGENT_WORDS for word in lead):
        return [AGENT, *rest]
    if lead and rest and isinstance(rest[0], int) and len(lead) == 1:
        return rest  # "Hand {0}", "Level {1}": the type's noun
    return items


def _generic_text(predicate: str, arity: int) -> str:
    words = predicate.replace("-", " ").replace("_", " ")
    if arity == 0:
        return words
    if arity == 1:
        return f"{{0}} is {words}"
    rest = " ".join(f"{{{k}}}" for k in range(1, arity))
    return f"{{0}} is {words} {rest}"


def _negated(items: tuple[Item, ...]) -> tuple[Item, ...] | None:
    """The items saying the fact is false: "not" after "be", else before the verb."""
    if "not" in items:
        return None
    if "be" in items:
        k = items.index("be") + 1
        return (*items[:k], "not", *items[k:])
    for k, item in enumerate(items):
        if isinstance(item, str) and item != AGENT and k > 0:
            return (*items[:k], "not", *items[k:])
    return None


def _variants(base: Template, arity: int) -> Iterator[Template]:
    """``base``, its converse and removal (phrases of place), its negation, and the forms
    that leave out an argument after a preposition."""
    items = base.items
    yield base
    forms = [base]
    if len(items) == 4 and items[1] == "be" and items[2] in _PLACE:
        a, b = items[0], items[3]
        if isinstance(a, int) and isinstance(b, int):
            for verb in ("contain", "have"):
                converse = Template(base.predicate, (b, verb, a), text=base.text)
                forms.append(converse)
                yield converse
            for removal in _REMOVALS:
                yield Template(
                    base.predicate, (a, "be", *removal, b), negative=True, text=base.text
                )
    for form in forms:
        negated = _negated(form.items)
        if negated is not None:
            yield Template(form.predicate, negated, negative=True, text=form.text)
    if arity >= 2:
        yield from _omissions(base)


def _omissions(base: Template) -> Iterator[Template]:
    items = base.items
    for k in range(1, len(items)):
        slot, before = items[k], items[k - 1]
        if not isinstance(slot, int) or not isinstance(before, str):
            continue
        if before not in _OMISSIBLE_AFTER or slot == items[0]:
            continue
        shorter = (*items[: k - 1], *items[k + 1 :])
        words = [i for i in shorter if isinstance(i, str) and i not in ("be", "not")]
        if not words or not any(isinstance(i, int) or i == AGENT for i in shorter):
            continue
        omitted = Template(
            base.predicate, shorter, base.negative, (*base.omitted, slot), base.text,
            base.agent_part,
        )  # fmt: skip
        yield omitted
        negated = _negated(shorter)
        if negated is not None and not base.negative:
            yield Template(
                base.predicate, negated, True, (*base.omitted, slot), base.text, base.agent_part
            )


@cache
def _domain_templates(
    domain_key: str, predicates: tuple[tuple[str, int], ...], phrases_key: str | None
) -> tuple[Template, ...]:
    table: Mapping[str, Phrase] = PHRASES.get(phrases_key or "", {})
    found: dict[tuple[str, tuple[Item, ...], bool, tuple[int, ...]], Template] = {}
    for predicate, arity in predicates:
        phrase = table.get(predicate)
        texts = (
            [phrase.now, phrase.goal, *([phrase.group] if phrase.group else [])]
            if phrase is not None
            else [_generic_text(predicate, arity)]
        )
        for text in texts:
            items = tuple(_template_items(text, arity))
            slots = {i for i in items if isinstance(i, int)}
            if slots != set(range(arity)):
                continue  # a phrase that leaves out an argument: only its full forms
            base = Template(predicate, items, text=text)
            for template in _variants(base, arity):
                key = (template.predicate, template.items, template.negative, template.omitted)
                found.setdefault(key, template)
    return tuple(found.values())


def _agent_part_templates(templates: Sequence[Template], lexicon: Lexicon) -> list[Template]:
    """Mark the templates about what an agent holds things with, and let "empty" and
    "free" stand for each other in them."""
    parts = {
        o
        for noun in lexicon.nouns
        if noun.words and noun.words[-1] in AGENT_PARTS
        for o in noun.objects
    }
    domain = lexicon.problem.domain
    out: list[Template] = []
    for template in templates:
        types = domain.predicates.get(template.predicate, ())
        about_parts = AGENT in template.items or any(
            isinstance(i, int)
            and i < len(types)
            and any(domain.is_subtype(lexicon.problem.all_objects.get(o), types[i]) for o in parts)
            and i == template.items[0]
            for i in template.items
        )
        if not about_parts:
            out.append(template)
            continue
        marked = Template(
            template.predicate, template.items, template.negative, template.omitted,
            template.text, True,
        )  # fmt: skip
        out.append(marked)
        items = template.items
        if len(items) >= 2 and items[-2] == "be" and items[-1] in (_EMPTY, _FREE):
            for words in (("be", "not", "hold", _ANYTHING), ("hold", _NOTHING)):
                out.append(
                    Template(
                        template.predicate,
                        (*items[:-2], *words),
                        template.negative,
                        template.omitted,
                        template.text,
                        True,
                    )
                )
        for a, b in ((_EMPTY, _FREE), (_FREE, _EMPTY)):
            if a in template.items:
                swapped = tuple(b if i == a else i for i in template.items)
                out.append(
                    Template(
                        template.predicate,
                        swapped,
                        template.negative,
                        template.omitted,
                        template.text,
                        True,
                    )
                )
    return out


def _possession_variants(templates: Sequence[Template]) -> list[Template]:
    """ "holds" for "carries" and the other way round, where the domain says only one of
    them ("robot1 holds ball1 in lgripper1" in grippers, whose phrase is "carries")."""
    verbs = ("carry", "hold")
    used = {i for t in templates for i in t.items if i in verbs}
    out = []
    for template in templates:
        items = template.items
        if (
            len(items) == 5
            and items[1] in verbs
            and items[3] == "in"
            and not template.negative
            and all(isinstance(items[k], int) for k in (0, 2, 4))
        ):
            # "lgripper1 holds ball1" for "robot1 carries ball1 in lgripper1": the holder
            # is then the one the task relates to that gripper
            holder, held, place = items[0], items[2], items[4]
            assert isinstance(holder, int)
            for verb in verbs:
                out.append(
                    Template(
                        template.predicate, (place, verb, held), False, (holder,), template.text
                    )
                )
        for verb in used & set(template.items):
            for other in set(verbs) - used:
                items = tuple(other if i == verb else i for i in template.items)
                out.append(
                    Template(
                        template.predicate,
                        items,
                        template.negative,
                        template.omitted,
                        template.text,
                        template.agent_part,
                    )
                )
    return out


# ----------------------------------------------------------------- the grammar


class Grammar:
    """The grammar of one task (its objects) in its domain's English."""

    def __init__(self, problem: Problem, domain: str | None = None) -> None:
        self.problem = problem
        self.domain_name = domain
        self.lexicon = Lexicon(problem, domain)
        predicates = tuple(sorted((p, len(t)) for p, t in problem.domain.predicates.items()))
        base = _domain_templates(problem.domain.name, predicates, domain)
        base = (*base, *_possession_variants(base))
        self.templates = _agent_part_templates(base, self.lexicon)
        self.agent_state = any(t.agent_part for t in self.templates)
        self.agent_templates = any(AGENT in t.items for t in self.templates)
        self.parts = tuple(
            o
            for noun in self.lexicon.nouns
            if noun.words and noun.words[-1] in AGENT_PARTS and not noun.plural
            and len(noun.words) == 1
            for o in noun.objects
        )  # fmt: skip
        if not self.agent_state:
            self.templates += list(_RELEASE_TEMPLATES)
        self.adjectives: dict[str, str] = {}
        for template in self.templates:
            items = template.items
            if (
                len(items) == 3
                and items[0] == 0
                and items[1] == "be"
                and isinstance(items[2], str)
                and not template.negative
                and not template.omitted
                and len(problem.domain.predicates.get(template.predicate, ())) == 1
            ):
                self.adjectives.setdefault(items[2], template.predicate)
        self.known = problem.init | problem.goal.positive
        words = {i for t in self.templates for i in t.items if isinstance(i, str)}
        # "ball1 is at room2" where the domain says "in" (and has no "at"): the same place
        self.place_synonyms = {"at": "in"} if "in" in words and "at" not in words else {}

    # -------------------------------------------------------------- noun phrases

    def mentions(
        self, toks: Sequence[Token], subject: tuple[Mention, ...] | None
    ) -> tuple[Mention, ...] | None:
        """The noun phrases of a coordinated list ("a, b, and c"), or None."""
        parts: list[list[Token]] = [[]]
        for token in toks:
            if token.raw in (",", "and"):
                if parts[-1]:
                    parts.append([])
                continue
            parts[-1].append(token)
        if not parts[-1]:
            parts.pop()
        if not parts:
            return None
        found = []
        for part in parts:
            mention = self.mention(part, subject)
            if mention is None:
                return None
            found.append(mention)
        if len(found) > 1 and any(m.mode in ("agent", "release") for m in found):
            return None
        return tuple(found)

    def mention(self, toks: Sequence[Token], subject: tuple[Mention, ...] | None) -> Mention | None:
        """One noun phrase (see the module docstring), or None."""
        if not toks:
            return None
        raw = tuple(t.raw for t in toks)
        text = " ".join(raw)
        k = 0
        mode: str | None = None
        related: list[str] = []
        if raw[0] in ("all", "every", "each", "both"):
            mode, k = "all", 1
            if raw[k : k + 2] == ("of", "the"):
                k += 2
            elif raw[k : k + 1] == ("the",):
                k += 1
        elif raw[0] in ("the", "this", "that", "these", "those"):
            mode, k = "the", 1
        elif raw[0] in ("a", "an", "some", "any", "one"):
            mode, k = "a", 1
        elif raw[0] in ("its", "their", "his", "her"):
            if not subject or len(subject) != 1 or len(subject[0].candidates) != 1:
                return None
            mode, k = "the", 1
            related = list(subject[0].candidates)
        elif "'s" in raw:
            cut = raw.index("'s")
            owner = self.mention(toks[:cut], subject)
            if owner is None or owner.mode == "agent" or len(owner.candidates) != 1:
                if owner is not None and owner.mode == "agent":
                    return self._agent(toks[cut + 1 :], "the", text)
                return None
            mode, k = "the", cut + 1
            related = list(owner.candidates)
        other = raw[k : k + 1] == ("other",)
        k += int(other)
        ordinal = None
        if k < len(raw):
            match = _NUMBERED_ORDINAL.match(raw[k])
            if raw[k] in _ORDINALS or match:
                ordinal = _ORDINALS.get(raw[k]) or int(match.group(1) if match else 0)
                k += 1
        head = list(toks[k:])
        # a relation after the noun: "the nuts on hub1", "the gripper of robot1"
        for p in range(1, len(head)):
            if head[p].raw in _RELATIONS or head[p].norm in _RELATIONS:
                owner = self.mention(head[p + 1 :], subject)
                single = owner is not None and len(owner.candidates) == 1
                if single and owner is not None and owner.mode in ("exact", "the", "a"):
                    related += list(owner.candidates)
                    head = head[:p]
                    break
        if not head:
            return None
        found = self._head(head, mode, ordinal, related, text)
        if found is None or not other:
            return found
        return Mention(
            found.text, found.candidates, found.mode, found.plural, found.conditions, True
        )

    def _head(
        self,
        head: Sequence[Token],
        mode: str | None,
        ordinal: int | None,
        related: Sequence[str],
        text: str,
    ) -> Mention | None:
        raw = tuple(t.raw for t in head)
        norms = tuple(t.norm for t in head)
        if ordinal is None and len(raw) <= self.lexicon.longest_name:
            named = self.lexicon.named(raw)
            if named:
                names = tuple(sorted(named, key=natural_key))
                if mode == "a":
                    return None
                return Mention(text, names, "exact" if len(names) == 1 else "the")
        found = self.lexicon.noun_at_end(norms)
        if found is None:
            return self._agent(head, mode, text)
        noun, start = found
        adjectives = norms[:start]
        predicates = [self.adjectives.get(a) for a in adjectives]
        if any(p is None for p in predicates):
            return None
        candidates = list(noun.objects)
        if related:
            candidates = [o for o in candidates if self._related(o, related)]
        if mode == "a":
            conditions = tuple(p for p in predicates if p)
        else:
            conditions = ()
            for predicate in predicates:
                candidates = [o for o in candidates if (predicate, o) in self.problem.init]
        if ordinal is not None:
            numbered = [o for o in candidates if self.lexicon.number_of(o) == ordinal]
            if not numbered and 0 < ordinal <= len(candidates):
                numbered = [candidates[ordinal - 1]]
            candidates = numbered
        if not candidates:
            return None
        if mode is None:
            mode = "the"
        plural = noun.plural or self.lexicon.is_plural(raw, len(noun.words))
        return Mention(text, tuple(candidates), mode, plural, conditions)

    def _agent(self, head: Sequence[Token], mode: str | None, text: str) -> Mention | None:
        """The agent (or what it holds things with) where the domain names no such objects."""
        norms = [t.norm for t in head]
        words = set(norms)
        agent = words <= _SELF or (
            words & AGENT_PARTS
            and not any(self.lexicon.has_noun(w) for w in words & AGENT_PARTS)
            and words <= AGENT_PARTS | _SELF | {"robot", "own"}
        )
        if not agent and not (words == {"robot"} and not self.lexicon.has_noun("robot")):
            return None
        if not self.agent_state:
            return Mention(text, (), "release")
        if not self.agent_templates and self.parts:
            # the agent of a domain whose hands are objects: said idle, all its hands are
            return Mention(text, self.parts, "parts", True)
        return Mention(text, (), "agent")

    def _related(self, obj: str, others: Sequence[str]) -> bool:
        return any(obj in fact[1:] and all(o in fact[1:] for o in others) for fact in self.known)

    # -------------------------------------------------------------- clauses

    def _type_distance(self, obj: str, type_name: str) -> int | None:
        """Steps from ``obj``'s type up to ``type_name`` (None: not of that type)."""
        domain: Domain = self.problem.domain
        actual = self.problem.all_objects.get(obj)
        if actual is None:
            return None
        if not domain.is_subtype(actual, type_name):
            return None
        if type_name == "object" and actual != "object":
            return 1 + _depth(domain, actual)
        steps, current = 0, actual
        current_type: str | None = current
        while current_type is not None and current_type != type_name and steps < 20:
            current_type = domain.types.get(current_type)
            steps += 1
        return steps

    def resolve(
        self, template: Template, bindings: Mapping[Item, tuple[Mention, ...]]
    ) -> Clause | str:
        """The facts a matched clause says, or why it names no fact of the task."""
        types = self.problem.domain.predicates[template.predicate]
        arity = len(types)
        slots = [k for k in range(arity) if k not in template.omitted]
        facts: list[tuple[bool, Fact]] = []
        others: list[tuple[Fact, str]] = []
        cost = template.cost
        notes: list[str] = []
        per_slot = [bindings.get(k, ()) for k in slots]
        for combination in itertools.product(*per_slot):
            chosen: dict[int, list[str]] = {}
            loose: dict[int, Mention] = {}
            for k, mention in zip(slots, combination, strict=True):
                if mention.mode in ("agent", "release"):
                    return f"'{mention.text}' is the agent, not an argument of {template.predicate}"
                fitting = []
                for obj in mention.candidates:
                    distance = self._type_distance(obj, types[k])
                    if distance is not None:
                        fitting.append((distance, obj))
                if not fitting:
                    names = ", ".join(mention.candidates[:3])
                    kinds = sorted(
                        {self.problem.all_objects.get(o, "?") for o in mention.candidates}
                    )
                    return (
                        f"'{mention.text}' ({names}: {'/'.join(kinds)}) cannot be argument "
                        f"{k + 1} of {template.predicate} (a {types[k]})"
                    )
                cost += min(d for d, _ in fitting)
                objects = [o for _, o in fitting]
                if mention.mode in ("all", "exact", "parts") or len(objects) == 1:
                    chosen[k] = objects
                else:
                    loose[k] = Mention(mention.text, tuple(objects), mention.mode, mention.plural)
            for fixed in itertools.product(*[[(k, o) for o in chosen[k]] for k in chosen]):
                args: dict[int, str] = dict(fixed)
                result = self._settle(template, types, args, loose, combination, slots)
                if isinstance(result, str):
                    return result
                for full in result:
                    fact = (template.predicate, *full)
                    facts.append((not template.negative, fact))
                    for k, mention in zip(slots, combination, strict=True):
                        if mention.other:
                            others.append((fact, full[k]))
            for k, mention in zip(slots, combination, strict=True):
                for predicate in mention.conditions:
                    for positive, fact in list(facts):
                        if positive:
                            obj = fact[1 + k]
                            facts.append((True, (predicate, obj)))
        if template.omitted:
            notes.append(f"{template.predicate}: an argument left out, read from the task")
        subject_item = template.items[0]
        subject = bindings.get(subject_item) if subject_item in bindings else None
        unique = list(dict.fromkeys(facts))
        return Clause(unique, cost, subject, notes, others)

    def _settle(
        self,
        template: Template,
        types: Sequence[str],
        args: dict[int, str],
        loose: Mapping[int, Mention],
        combination: Sequence[Mention],
        slots: Sequence[int],
    ) -> list[tuple[str, ...]] | str:
        """Complete ``args``: the phrases that name several objects, and the arguments
        left out, from the task's initial state and goal (see the module docstring)."""
        arity = len(types)
        picks = itertools.product(*[[(k, o) for o in loose[k].candidates] for k in loose])
        full: list[tuple[str, ...]] = []
        problem = ""
        for pick in picks:
            chosen = {**args, **dict(pick)}
            for k in template.omitted:
                found = self._left_out(template.predicate, types[k], list(chosen.values()))
                if len(found) != 1:
                    what = "no" if not found else f"{len(found)} ({', '.join(found[:4])})"
                    related = ", ".join(chosen.values()) or "it"
                    problem = (
                        f"{template.predicate}: argument {k + 1} is left out and the task has "
                        f"{what} {types[k]} related to {related}"
                    )
                    break
                chosen[k] = found[0]
            else:
                full.append(tuple(chosen[k] for k in range(arity)))
        if not loose:
            return full or problem
        if not full:
            return problem
        goal = self.problem.goal.positive
        indefinite = any(m.mode == "a" for m in loose.values())
        facts_in = [f for f in full if (template.predicate, *f) in goal] if indefinite else []
        facts_in = facts_in or [f for f in full if (template.predicate, *f) in self.known]
        plural = all(m.plural and m.mode != "a" for m in loose.values())
        if not facts_in or (len(facts_in) > 1 and not plural):
            mention = next(iter(loose.values()))
            many = ", ".join(mention.candidates[:4]) + (
                ", ..." if len(mention.candidates) > 4 else ""
            )
            return f"'{mention.text}' is ambiguous here: it may name {many}"
        return facts_in

    def _left_out(self, predicate: str, type_name: str, bound: Sequence[str]) -> list[str]:
        """The objects of ``type_name`` the task relates to ``bound`` (in a fact of its
        initial state or goal; in one of ``predicate`` when there are such)."""
        found = sorted(
            {
                o
                for o in self.problem.all_objects
                if o not in bound
                and self._type_distance(o, type_name) is not None
                and self._related(o, bound)
            },
            key=natural_key,
        )
        same = [
            o
            for o in found
            if any(
                f[0] == predicate and o in f[1:] and all(b in f[1:] for b in bound)
                for f in self.known
            )
        ]
        if same or found or len(bound) < 2:
            return same or found
        # related to one of them ("lgripper1 holds ball1": the robot of that gripper)
        return sorted(
            {o for b in bound for o in self._left_out(predicate, type_name, [b])},
            key=natural_key,
        )


def _depth(domain: Domain, type_name: str) -> int:
    depth, current = 0, domain.types.get(type_name)
    while current is not None and depth < 20:
        depth += 1
        current = domain.types.get(current)
    return depth


# ----------------------------------------------------------------- sentences


@dataclass
class Reading:
    """A whole sentence read: its facts, and notes on how (omitted arguments, ...)."""

    positive: list[Fact]
    negative: list[Fact]
    notes: list[str]
    cost: int


class _Parser:
    """One sentence against one grammar (memoised on the position and the subject)."""

    def __init__(self, grammar: Grammar, toks: Sequence[Token]) -> None:
        self.grammar = grammar
        self.toks = list(toks)
        self.failure: Failure | None = None
        self._memo: dict[tuple[int, int], tuple[int, list[Clause]] | None] = {}
        self._subjects: list[tuple[Mention, ...] | None] = [None]
        self._np: dict[tuple[int, int, int], tuple[Mention, ...] | None] = {}

    def fail(self, position: int, reason: str, semantic: bool) -> None:
        failure = Failure(position, reason, semantic)
        if failure.better(self.failure):
            self.failure = failure

    def _subject_id(self, subject: tuple[Mention, ...] | None) -> int:
        for k, known in enumerate(self._subjects):
            if known == subject:
                return k
        self._subjects.append(subject)
        return len(self._subjects) - 1

    def mentions(
        self, i: int, j: int, subject: tuple[Mention, ...] | None
    ) -> tuple[Mention, ...] | None:
        key = (i, j, self._subject_id(subject))
        if key not in self._np:
            self._np[key] = self.grammar.mentions(self.toks[i:j], subject)
        return self._np[key]

    def _boundary(self, j: int) -> bool:
        return j >= len(self.toks) or self.toks[j].raw in CONJUNCTIONS

    def match(
        self,
        items: Sequence[Item],
        i: int,
        bindings: dict[Item, tuple[Mention, ...]],
        subject: tuple[Mention, ...] | None,
    ) -> Iterator[tuple[int, dict[Item, tuple[Mention, ...]]]]:
        if not items:
            yield i, bindings
            return
        item, rest = items[0], items[1:]
        toks = self.toks
        if isinstance(item, int) or item == AGENT:
            if item in bindings:  # the subject of an elliptic clause
                yield from self.match(rest, i, bindings, subject)
                return
            end = min(len(toks), i + _MAX_SPAN)
            # "its" names the clause's own subject once there is one
            context = next(iter(bindings.values()), subject)
            for j in range(end, i, -1):
                if not rest and not self._boundary(j):
                    continue
                found = self.mentions(i, j, context)
                if found is None:
                    continue
                agentish = all(m.mode in ("agent", "release") for m in found)
                if (item == AGENT) != agentish:
                    continue
                yield from self.match(rest, j, {**bindings, item: found}, subject)
            return
        j = i
        while j < len(toks) and (toks[j].raw in ARTICLES or toks[j].raw in _FILLERS):
            j += 1
        if item != "be" and j + 1 < len(toks) and toks[j].norm == "be" and toks[j + 1].norm == item:
            j += 1  # "is holding" says what "holds" says
        if j < len(toks) and toks[j].norm == item:
            yield from self.match(rest, j + 1, bindings, subject)

    def clause_options(
        self, i: int, subject: tuple[Mention, ...] | None
    ) -> Iterator[tuple[int, Clause]]:
        grammar = self.grammar
        for template in grammar.templates:
            yield from self._read(template, template.items, i, {}, subject)
        if subject is None:
            return
        for template in grammar.templates:
            first = template.items[0]
            if not (isinstance(first, int) or first == AGENT):
                continue
            agentish = all(m.mode in ("agent", "release") for m in subject)
            if (first == AGENT) != agentish:
                continue
            rest = template.items[1:]
            starts = [rest]
            if rest and rest[0] == "be":
                starts.append(rest[1:])
            for items in starts:
                if items:
                    yield from self._read(template, items, i, {first: subject}, subject)

    def _read(
        self,
        template: Template,
        items: Sequence[Item],
        i: int,
        bound: dict[Item, tuple[Mention, ...]],
        subject: tuple[Mention, ...] | None,
    ) -> Iterator[tuple[int, Clause]]:
        for j, bindings in self.match(items, i, dict(bound), subject):
            if not self._boundary(j):
                continue
            if template.predicate == RELEASE:
                yield j, Clause([], 0, bindings.get(AGENT), [_RELEASE_NOTE])
                continue
            if not template.idle and any(m.mode == "parts" for ms in bindings.values() for m in ms):
                continue
            clause = self.grammar.resolve(template, bindings)
            if isinstance(clause, str):
                self.fail(i, clause, True)
                continue
            yield j, clause

    def parse(self, i: int, subject: tuple[Mention, ...] | None) -> tuple[int, list[Clause]] | None:
        """The cheapest reading of the sentence from ``i`` (cost, clauses), or None."""
        toks = self.toks
        while i < len(toks) and (toks[i].raw in CONJUNCTIONS or toks[i].raw in _FILLERS):
            i += 1
        i = self._skip_lead(i)
        if i >= len(toks):
            return 0, []
        key = (i, self._subject_id(subject))
        if key in self._memo:
            return self._memo[key]
        self._memo[key] = None  # no reading through a cycle
        best: tuple[int, list[Clause]] | None = None
        ties: list[list[Clause]] = []
        for j, clause in self.clause_options(i, subject):
            if j <= i:
                continue
            rest = self.parse(j, clause.subject if clause.subject is not None else subject)
            if rest is None:
                continue
            total = clause.cost + rest[0]
            reading = [clause, *rest[1]]
            if best is None or total < best[0]:
                best, ties = (total, reading), [reading]
            elif total == best[0]:
                ties.append(reading)
        if best is None:
            self.fail(i, _no_phrase(toks, i), False)
        elif len({_facts_key(r) for r in ties}) > 1:
            self.fail(i, _two_readings(toks, i, ties), True)
            best = None
        self._memo[key] = best
        return best

    def _skip_lead(self, i: int) -> int:
        raws = [t.raw for t in self.toks]
        for lead in _LEADS:
            if tuple(raws[i : i + len(lead)]) == lead:
                i += len(lead)
                while i < len(raws) and raws[i] == ",":
                    i += 1
                return i
        return i


_RELEASE_NOTE = "says the agent holds nothing: this domain has no agent state, nothing to add"


def _facts_key(reading: Sequence[Clause]) -> frozenset[tuple[bool, Fact]]:
    return frozenset(f for clause in reading for f in clause.facts)


def _clause_text(toks: Sequence[Token], i: int) -> str:
    words = []
    for token in toks[i:]:
        if token.raw in CONJUNCTIONS and token.raw != "and":
            break
        words.append(token.raw)
        if len(words) >= 12:
            words.append("...")
            break
    return " ".join(words)


def _no_phrase(toks: Sequence[Token], i: int) -> str:
    return f"no phrase of the domain reads '{_clause_text(toks, i)}'"


def _two_readings(toks: Sequence[Token], i: int, readings: Sequence[Sequence[Clause]]) -> str:
    return f"'{_clause_text(toks, i)}' reads {len({_facts_key(r) for r in readings})} ways"


_LABEL = re.compile(
    r"^\W*(?:agent\s*\d+(?:'s)?\s*(?:sub)?goal(?:\s+condition)?|(?:final\s+)?(?:sub)?goal"
    r"(?:\s+condition)?)\W*:\W*",
    re.IGNORECASE,
)


def read_sentence(grammar: Grammar, sentence: str) -> Reading:
    """The facts ``sentence`` says about the grammar's task; :class:`ReadError` with the
    reason when it cannot be read, or reads several ways."""
    text = _LABEL.sub("", sentence.strip())
    toks = [
        Token(t.raw, grammar.place_synonyms.get(t.norm, t.norm)) for t in normalise(tokens(text))
    ]
    if not toks:
        raise ReadError("an empty subgoal")
    parser = _Parser(grammar, toks)
    result = parser.parse(0, None)
    if result is None:
        failure = parser.failure
        raise ReadError(failure.reason if failure is not None else _no_phrase(toks, 0))
    cost, clauses = result
    positive: list[Fact] = []
    negative: list[Fact] = []
    notes: list[str] = []
    for k, clause in enumerate(clauses):
        named = {
            t for other in clauses[:k] + clauses[k + 1 :] for _, f in other.facts for t in f[1:]
        }
        left_out = {fact for fact, obj in clause.others if obj in named}
        for is_positive, fact in clause.facts:
            if fact not in left_out:
                (positive if is_positive else negative).append(fact)
        notes += [n for n in clause.notes if n not in notes]
    positive = list(dict.fromkeys(positive))
    negative = list(dict.fromkeys(negative))
    clash = set(positive) & set(negative)
    if clash:
        fact = sorted(clash)[0]
        raise ReadError(f"says both {fact} and its negation")
    if not positive and not negative:
        raise ReadError("names no condition of the task (" + "; ".join(notes or ["nothing"]) + ")")
    return Reading(positive, negative, notes, cost)


__all__ = ["AGENT", "Grammar", "Mention", "ReadError", "Reading", "Template", "read_sentence"]
