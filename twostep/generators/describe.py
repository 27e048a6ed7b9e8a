"""English descriptions of planning tasks, for the LLM prompts (the ``.nl`` files).

:func:`describe_problem` picks the describer of the task's domain (barman, blocksworld,
grippers, termes, tyreworld) or, for any other domain, the generic one that writes each
fact as ``pred(a, b) is true``. Every describer names all objects of the goal and lists
facts in a fixed order, so the text is a deterministic function of the problem. Domain
describers phrase the facts they know and fall back to the generic wording for the rest,
so they also work on states the generator never makes (e.g. after a helper's plan).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

from twostep.pddl import Fact, Problem

Describer = Callable[[Problem], str]


@dataclass(frozen=True)
class Phrase:
    """How to say a fact: ``now`` for the state, ``goal`` for the goal, ``{0}`` = 1st term.

    ``group`` says several state facts at once that differ only in their first term
    (``{0}`` is then the joined list); goal templates serve both cases.
    """

    now: str
    goal: str
    group: str | None = None


# ----------------------------------------------------------------- helpers


def natural_key(name: str) -> tuple[tuple[int, int | str], ...]:
    """Sort key that puts ``b2`` before ``b10``."""
    return tuple(
        (0, int(part)) if part.isdigit() else (1, part) for part in re.split(r"(\d+)", name) if part
    )


def fact_key(fact: Fact) -> tuple[tuple[tuple[int, int | str], ...], ...]:
    return tuple(natural_key(term) for term in fact)


def join(names: Iterable[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    items = list(names)
    if len(items) <= 1:
        return "".join(items)
    return ", ".join(items[:-1]) + " and " + items[-1]


def plural(count: int, noun: str, nouns: str | None = None) -> str:
    return f"{count} {noun if count == 1 else nouns or noun + 's'}"


def objects_of(problem: Problem, type_name: str, *predicates: str) -> list[str]:
    """Objects of ``type_name``; for untyped files, the objects used by ``predicates``."""
    found = {o for o, t in problem.all_objects.items() if t == type_name}
    if not found:
        facts = problem.init | problem.goal.positive
        found = {term for fact in facts if fact[0] in predicates for term in fact[1:]}
    return sorted(found, key=natural_key)


def generic_fact(fact: Fact) -> str:
    return f"{fact[0]}({', '.join(fact[1:])})" if len(fact) > 1 else fact[0]


def sentences(
    facts: Iterable[Fact], phrases: Mapping[str, Phrase], goal: bool = False
) -> list[str]:
    """One sentence per fact, in table order, then the facts the table does not know.

    Facts whose phrase has a ``group`` form and that differ only in their first term are
    said together: ``r1 and r2 are in boot``.
    """
    order = {pred: i for i, pred in enumerate(phrases)}
    ordered = sorted(facts, key=lambda f: (order.get(f[0], len(order)), fact_key(f)))
    slots: list[str | Fact] = []  # a finished sentence, or the key of a group
    subjects: dict[Fact, list[str]] = {}
    for fact in ordered:
        phrase = phrases.get(fact[0])
        if phrase is None:
            slots.append(f"{generic_fact(fact)} {'should be' if goal else 'is'} true.")
        elif phrase.group is not None and len(fact) > 1:
            key = (fact[0], *fact[2:])
            if key not in subjects:
                subjects[key] = []
                slots.append(key)
            subjects[key].append(fact[1])
        else:
            slots.append((phrase.goal if goal else phrase.now).format(*fact[1:]) + ".")
    lines = []
    for slot in slots:
        if isinstance(slot, str):
            lines.append(slot)
            continue
        phrase, names = phrases[slot[0]], subjects[slot]
        template = phrase.goal if goal else phrase.now if len(names) == 1 else str(phrase.group)
        lines.append(template.format(join(names), *slot[1:]) + ".")
    return lines


def negative_sentences(facts: Iterable[Fact], phrases: Mapping[str, Phrase]) -> list[str]:
    lines = []
    for fact in sorted(facts, key=fact_key):
        phrase = phrases.get(fact[0])
        said = phrase.now.format(*fact[1:]) if phrase else f"{generic_fact(fact)} is true"
        lines.append(f"It should not be the case that {said}.")
    return lines


def _text(*parts: str | list[str]) -> str:
    lines: list[str] = []
    for part in parts:
        lines += [part] if isinstance(part, str) else part
    return "\n".join(line for line in lines if line) + "\n"


# ----------------------------------------------------------------- generic


def describe_generic(problem: Problem) -> str:
    """Any domain: the objects by type, then every initial and goal fact, grouped."""
    by_type: dict[str, list[str]] = {}
    for obj, type_name in problem.all_objects.items():
        by_type.setdefault(type_name, []).append(obj)
    header = [f"This is a task of the '{problem.domain.name}' domain."]
    for type_name in sorted(by_type, key=natural_key):
        names = sorted(by_type[type_name], key=natural_key)
        kind = "object" if type_name == "object" else f"{type_name} object"
        header.append(
            f"There {'is' if len(names) == 1 else 'are'} {plural(len(names), kind)}: {join(names)}."
        )
    init = ["In the initial state these facts are true (all others are false):"]
    basic = (f for f in problem.init if not problem.domain.is_derived(f))
    init += [f"{generic_fact(f)} is true." for f in sorted(basic, key=fact_key)]
    goal = ["Your goal is to reach a state where:"]
    goal += [f"{generic_fact(f)} is true." for f in sorted(problem.goal.positive, key=fact_key)]
    goal += [f"{generic_fact(f)} is false." for f in sorted(problem.goal.negative, key=fact_key)]
    if not problem.goal.is_conjunction:  # a quantified goal: said as written
        goal.append(f"this condition holds: {problem.goal.to_pddl()}.")
    return _text(header, init, goal)


# ----------------------------------------------------------------- blocksworld

BLOCKSWORLD = {
    "on": Phrase("{0} is on top of {1}", "{0} should be on top of {1}"),
    "on-table": Phrase("{0} is on the table", "{0} should be on the table", "{0} are on the table"),
    "clear": Phrase("{0} is clear", "{0} should be clear", "{0} are clear"),
    "holding": Phrase("You are holding {0}", "You should be holding {0}"),
    "arm-empty": Phrase("Your arm is empty", "Your arm should be empty"),
}


def describe_blocksworld(problem: Problem) -> str:
    blocks = objects_of(problem, "block", "on", "on-table", "clear", "holding")
    return _text(
        f"You have {plural(len(blocks), 'block')}: {join(blocks)}.",
        sentences(problem.init, BLOCKSWORLD),
        "Your goal is to rearrange the blocks so that:",
        sentences(problem.goal.positive, BLOCKSWORLD, goal=True),
        negative_sentences(problem.goal.negative, BLOCKSWORLD),
    )


# ----------------------------------------------------------------- grippers

GRIPPERS = {
    "at-robby": Phrase("{0} is in {1}", "{0} should be in {1}"),
    "at": Phrase("{0} is in {1}", "{0} should be in {1}", "{0} are in {1}"),
    "carry": Phrase("{0} carries {1} in {2}", "{0} should carry {1} in {2}"),
    "free": Phrase("{1} of {0} is free", "{1} of {0} should be free"),
}


def grippers_balls(problem: Problem) -> list[str]:
    """The balls of a grippers task: what is somewhere or carried (balls are untyped)."""
    return sorted(
        {f[1] for f in problem.init | problem.goal.positive if f[0] == "at"}
        | {f[2] for f in problem.init if f[0] == "carry"},
        key=natural_key,
    )


def describe_grippers(problem: Problem) -> str:
    robots = objects_of(problem, "robot", "at-robby")
    rooms = objects_of(problem, "room", "at-robby")
    balls = grippers_balls(problem)
    owned: dict[str, set[str]] = {r: set() for r in robots}
    for fact in problem.init:
        if fact[0] in ("free", "carry") and fact[1] in owned:
            owned[fact[1]].add(fact[-1])
    hands = [f"{r} has {join(sorted(owned[r], key=natural_key)) or 'no gripper'}" for r in robots]
    state = set(problem.init)
    free = {f for f in state if f[0] == "free"}
    all_free = bool(free) and len(free) == sum(len(g) for g in owned.values())
    lines = sentences(state - free if all_free else state, GRIPPERS)
    if all_free:
        lines.append("All grippers are free.")
    return _text(
        f"You control {plural(len(robots), 'robot')}"
        f"{', each' if len(robots) > 1 else ''} with a left and a right gripper "
        f"({'; '.join(hands)}).",
        f"There are {plural(len(rooms), 'room')} ({join(rooms)}) "
        f"and {plural(len(balls), 'ball')} ({join(balls)}).",
        lines,
        "Your goal is to bring the balls to their destinations:",
        sentences(problem.goal.positive, GRIPPERS, goal=True),
        negative_sentences(problem.goal.negative, GRIPPERS),
    )


# ----------------------------------------------------------------- barman

BARMAN = {
    "handempty": Phrase("Hand {0} is empty", "Hand {0} should be empty", "Hands {0} are empty"),
    "holding": Phrase("Hand {0} holds {1}", "Hand {0} should hold {1}"),
    "ontable": Phrase("{0} is on the table", "{0} should be on the table", "{0} are on the table"),
    "clean": Phrase("{0} is clean", "{0} should be clean", "{0} are clean"),
    "empty": Phrase("{0} is empty", "{0} should be empty", "{0} are empty"),
    "contains": Phrase("{0} contains {1}", "{0} should contain {1}", "{0} contain {1}"),
    "used": Phrase("{0} has held {1} and is not clean", "{0} should have held {1}"),
    "shaker-level": Phrase(
        "{0} is filled to level {1}",
        "{0} should be filled to level {1}",
        "{0} are filled to level {1}",
    ),
    "shaker-empty-level": Phrase(
        "The empty level of {0} is {1}",
        "The empty level of {0} should be {1}",
        "The empty level of {0} is {1}",
    ),
    "next": Phrase("Level {1} is one shot above level {0}", "Level {1} should follow {0}"),
    "unshaked": Phrase(
        "{0} holds a mix not shaken yet",
        "{0} should hold an unshaken mix",
        "{0} hold a mix not shaken yet",
    ),
    "shaked": Phrase("{0} has been shaken", "{0} should be shaken", "{0} have been shaken"),
    "dispenses": Phrase("{0} dispenses {1}", "{0} should dispense {1}"),
    "cocktail-part1": Phrase(
        "The first ingredient of {0} is {1}", "The first ingredient of {0} should be {1}"
    ),
    "cocktail-part2": Phrase(
        "The second ingredient of {0} is {1}", "The second ingredient of {0} should be {1}"
    ),
}


def barman_shots(problem: Problem) -> list[str]:
    """The shot glasses of a barman task (untyped files: what can contain, but no shaker)."""
    shakers = objects_of(problem, "shaker", "shaker-level")
    return [s for s in objects_of(problem, "shot", "contains") if s not in shakers]


def describe_barman(problem: Problem) -> str:
    shakers = objects_of(problem, "shaker", "shaker-level")
    shots = barman_shots(problem)
    levels = objects_of(problem, "level", "next")
    dispensers = objects_of(problem, "dispenser", "dispenses")
    ingredients = objects_of(problem, "ingredient", "dispenses")
    cocktails = objects_of(problem, "cocktail", "cocktail-part1")
    served = len(problem.goal.positive)
    return _text(
        f"You have {plural(len(shakers), 'shaker')} ({join(shakers)}) with levels "
        f"{join(levels)}, {plural(len(shots), 'shot glass', 'shot glasses')} ({join(shots)}), "
        f"{plural(len(dispensers), 'dispenser')} ({join(dispensers)}) for "
        f"{plural(len(ingredients), 'ingredient')} ({join(ingredients)}), and two hands, "
        "left and right.",
        f"There {'is' if len(cocktails) == 1 else 'are'} "
        f"{plural(len(cocktails), 'cocktail recipe')} ({join(cocktails)}).",
        sentences(problem.init, BARMAN),
        f"Your goal is to serve {plural(served, 'drink')}:",
        sentences(problem.goal.positive, BARMAN, goal=True),
        negative_sentences(problem.goal.negative, BARMAN),
    )


# ----------------------------------------------------------------- termes

TERMES = {
    "at": Phrase("The robot is at {0}", "The robot should be at {0}"),
    "has-block": Phrase("The robot is carrying a block", "The robot should carry a block"),
    "is-depot": Phrase(
        "The depot, where blocks are created and destroyed, is at {0}", "{0} should be a depot"
    ),
    "height": Phrase("{0} is at height {1}", "The height at {0} should be {1}"),
    "neighbor": Phrase("{1} is next to {0}", "{1} should be next to {0}"),
    "succ": Phrase("Height {0} is one block above height {1}", "{0} should follow {1}"),
}
_GRID_NAME = re.compile(r"^pos-(\d+)-(\d+)$")


def _grid(positions: list[str]) -> tuple[int, int] | None:
    """(rows, columns) when the positions are exactly ``pos-R-C`` of a full grid."""
    cells = [_GRID_NAME.match(p) for p in positions]
    if not positions or not all(cells):
        return None
    coords = {(int(m.group(1)), int(m.group(2))) for m in cells if m}
    rows = max(r for r, _ in coords) + 1
    cols = max(c for _, c in coords) + 1
    return (rows, cols) if len(coords) == rows * cols == len(positions) else None


def _grid_neighbors(rows: int, cols: int) -> set[Fact]:
    facts: set[Fact] = set()
    for r in range(rows):
        for c in range(cols):
            for r2, c2 in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
                if 0 <= r2 < rows and 0 <= c2 < cols:
                    facts.add(("neighbor", f"pos-{r}-{c}", f"pos-{r2}-{c2}"))
    return facts


def _heights(facts: Iterable[Fact], numbers: list[str], verbs: tuple[str, str]) -> list[str]:
    """One sentence per height value listing the positions at that height."""
    at: dict[str, list[str]] = {}
    for fact in facts:
        if fact[0] == "height":
            at.setdefault(fact[2], []).append(fact[1])
    order = {n: i for i, n in enumerate(numbers)}
    lines = []
    for number in sorted(at, key=lambda n: (order.get(n, len(order)), natural_key(n))):
        where = sorted(at[number], key=natural_key)
        lines.append(f"{join(where)} {verbs[len(where) > 1]} height {number}.")
    return lines


def describe_termes(problem: Problem) -> str:
    positions = objects_of(problem, "position", "height")
    numbers = objects_of(problem, "numb", "succ")
    grid = _grid(positions)
    init = set(problem.init)
    layout: list[str]
    if grid is not None and {f for f in init if f[0] == "neighbor"} == _grid_neighbors(*grid):
        rows, cols = grid
        init = {f for f in init if f[0] != "neighbor"}
        layout = [
            f"The robot is on a grid with {plural(rows, 'row')} and {plural(cols, 'column')}:"
        ]
        layout += [" ".join(f"pos-{r}-{c}" for c in range(cols)) for r in range(rows)]
        layout.append(
            "The robot can move between positions next to each other in a row or "
            "a column, up or down by at most one block."
        )
    else:
        layout = [f"The robot works on {plural(len(positions), 'position')}: {join(positions)}."]
    succ = {f for f in init if f[0] == "succ"}
    if numbers and len(succ) == len(numbers) - 1:
        init -= succ
        layout.append(
            f"Heights go from {numbers[0]} (no block) up to {numbers[-1]} "
            f"({plural(len(numbers) - 1, 'block')}), one block per step."
        )
    carrying = ("has-block",) in init
    goal_lines = _heights(problem.goal.positive, numbers, ("should be at", "should be at"))
    goal_lines += sentences({f for f in problem.goal.positive if f[0] != "height"}, TERMES, True)
    if ("has-block",) in problem.goal.negative:
        goal_lines.append("The robot must not be holding a block at the end.")
    goal_lines += negative_sentences(problem.goal.negative - {("has-block",)}, TERMES)
    return _text(
        layout,
        _heights(init, numbers, ("is at", "are at")),
        sentences({f for f in init if f[0] != "height"}, TERMES),
        "" if carrying else "The robot is not carrying a block.",
        "Your goal is to build blocks so that:",
        goal_lines,
    )


# ----------------------------------------------------------------- tyreworld

TYREWORLD = {
    "in": Phrase("{0} is in {1}", "{0} should be in {1}", "{0} are in {1}"),
    "unlocked": Phrase("{0} is unlocked", "{0} should be unlocked"),
    "closed": Phrase("{0} is closed", "{0} should be closed"),
    "opened": Phrase("{0} is open", "{0} should be open"),
    "open": Phrase("{0} is open", "{0} should be open"),
    "have": Phrase(
        "{0} is out and ready to use",
        "{0} should be out and ready to use",
        "{0} are out and ready to use",
    ),
    "intact": Phrase("{0} is intact", "{0} should be intact", "{0} are intact"),
    "not-inflated": Phrase("{0} is not inflated", "{0} should be deflated", "{0} are not inflated"),
    "inflated": Phrase("{0} is inflated", "{0} should be inflated", "{0} are inflated"),
    "on": Phrase("{0} is on {1}", "{0} should be on {1}"),
    "on-ground": Phrase(
        "{0} is on the ground", "{0} should be on the ground", "{0} are on the ground"
    ),
    "not-on-ground": Phrase("{0} is jacked up", "{0} should be jacked up", "{0} are jacked up"),
    "free": Phrase(
        "{0} has no wheel on it", "{0} should have no wheel", "{0} have no wheel on them"
    ),
    "tight": Phrase("{0} is tight on {1}", "{0} should be tight on {1}"),
    "loose": Phrase("{0} is loose on {1}", "{0} should be loose on {1}"),
    "fastened": Phrase("{0} is fastened", "{0} should be fastened", "{0} are fastened"),
    "unfastened": Phrase("{0} is unfastened", "{0} should be unfastened", "{0} are unfastened"),
}


def tyreworld_wheels(problem: Problem, intact: bool | None = None) -> list[str]:
    """The wheels of a tyreworld task: the intact ones (``intact=True``, intact at the
    start), the flat ones (``False``), or all."""
    wheels = objects_of(problem, "wheel", "intact", "inflated")
    if intact is None:
        return wheels
    return [w for w in wheels if (("intact", w) in problem.init) == intact]


def describe_tyreworld(problem: Problem) -> str:
    objects = problem.all_objects
    tools = sorted((o for o, t in objects.items() if t == "tool"), key=natural_key)
    boots = objects_of(problem, "container", "closed", "unlocked")
    hubs = objects_of(problem, "hub", "fastened", "on-ground")
    nuts = objects_of(problem, "nut", "tight", "loose")
    intact, flat = tyreworld_wheels(problem, True), tyreworld_wheels(problem, False)
    parts = [f"a {tool}" for tool in tools] + [f"the container {b}" for b in boots]
    for noun, names in (("hub", hubs), ("nut", nuts), ("flat tyre", flat), ("intact tyre", intact)):
        if names:
            parts.append(f"{plural(len(names), noun)} ({join(names)})")
    return _text(
        f"You have {join(parts)}.",
        sentences(problem.init, TYREWORLD),
        "Your goal is to replace the flat tyres with intact ones, so that:",
        sentences(problem.goal.positive, TYREWORLD, goal=True),
        negative_sentences(problem.goal.negative, TYREWORLD),
    )


# ----------------------------------------------------------------- registry

DESCRIBERS: Mapping[str, Describer] = {
    "barman": describe_barman,
    "blocksworld": describe_blocksworld,
    "blocksworld-4ops": describe_blocksworld,  # the PDDL name of the blocksworld domain
    "grippers": describe_grippers,
    "gripper-strips": describe_grippers,  # the PDDL name of the grippers domain
    "termes": describe_termes,
    "tyreworld": describe_tyreworld,
}


def describe_problem(problem: Problem, domain: str | None = None) -> str:
    """The English description of ``problem``.

    ``domain`` picks the describer (default: the PDDL domain's name); unknown domains get
    :func:`describe_generic`.
    """
    return DESCRIBERS.get(domain or problem.domain.name, describe_generic)(problem)


# ----------------------------------------------------------------- nouns and phrases
#
# The words the describers use, as data, for readers of English about a task (the rules
# translator, twostep.english): the phrase table of each domain (how each predicate is
# said) and the common nouns the descriptions use for its objects ("4 shot glasses
# (shot1, ..., shot4)"), each with the describer's own choice of objects.


@dataclass(frozen=True)
class Noun:
    """A common noun the descriptions use for some objects of a task (``select``)."""

    singular: str
    plural: str
    select: Callable[[Problem], list[str]]


def _typed(type_name: str, *predicates: str) -> Callable[[Problem], list[str]]:
    return lambda problem: objects_of(problem, type_name, *predicates)


def _named(select: Callable[[Problem], list[str]], *starts: str) -> Callable[[Problem], list[str]]:
    """The objects of ``select`` whose name starts with one of ``starts`` (grippers'
    ``lgripper1`` is a left gripper) or contains its first one (``left1``)."""
    return lambda problem: [
        o for o in select(problem) if o.startswith(starts) or starts[0] in o.lower()
    ]


_GRIPPERS_GRIPPERS = _typed("gripper", "free")
_HUBS = _typed("hub", "fastened", "on-ground")

NOUNS: Mapping[str, tuple[Noun, ...]] = {
    "blocksworld": (
        Noun("block", "blocks", _typed("block", "on", "on-table", "clear", "holding")),
    ),
    "grippers": (
        Noun("robot", "robots", _typed("robot", "at-robby")),
        Noun("room", "rooms", _typed("room", "at-robby")),
        Noun("ball", "balls", grippers_balls),
        Noun("gripper", "grippers", _GRIPPERS_GRIPPERS),
        Noun("left gripper", "left grippers", _named(_GRIPPERS_GRIPPERS, "left", "l")),
        Noun("right gripper", "right grippers", _named(_GRIPPERS_GRIPPERS, "right", "r")),
    ),
    "barman": (
        Noun("shaker", "shakers", _typed("shaker", "shaker-level")),
        Noun("shot glass", "shot glasses", barman_shots),
        Noun("level", "levels", _typed("level", "next")),
        Noun("dispenser", "dispensers", _typed("dispenser", "dispenses")),
        Noun("ingredient", "ingredients", _typed("ingredient", "dispenses")),
        Noun("cocktail", "cocktails", _typed("cocktail", "cocktail-part1")),
        Noun("cocktail recipe", "cocktail recipes", _typed("cocktail", "cocktail-part1")),
        Noun("hand", "hands", _typed("hand", "handempty")),
    ),
    "termes": (Noun("position", "positions", _typed("position", "height")),),
    "tyreworld": (
        Noun("hub", "hubs", _HUBS),
        Noun("nut", "nuts", _typed("nut", "tight", "loose")),
        Noun("flat tyre", "flat tyres", lambda p: tyreworld_wheels(p, False)),
        Noun("intact tyre", "intact tyres", lambda p: tyreworld_wheels(p, True)),
        Noun("tyre", "tyres", tyreworld_wheels),
        Noun("wheel", "wheels", tyreworld_wheels),
        Noun("container", "containers", _typed("container", "closed", "unlocked")),
    ),
}

PHRASES: Mapping[str, Mapping[str, Phrase]] = {
    "barman": BARMAN,
    "blocksworld": BLOCKSWORLD,
    "grippers": GRIPPERS,
    "termes": TERMES,
    "tyreworld": TYREWORLD,
}

# The PDDL names of the domains whose folder has another name (as DESCRIBERS).
DOMAIN_ALIASES: Mapping[str, str] = {
    "blocksworld-4ops": "blocksworld",
    "gripper-strips": "grippers",
}


def describer_domain(problem: Problem, domain: str | None = None) -> str | None:
    """The domain whose phrases and nouns describe ``problem`` (None: the generic one):
    ``domain`` (a data folder's name) when it has a describer, else the PDDL name's."""
    for name in (domain, problem.domain.name):
        if name is None:
            continue
        name = DOMAIN_ALIASES.get(name, name)
        if name in PHRASES:
            return name
    return None
