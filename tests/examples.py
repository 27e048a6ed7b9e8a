"""Named example problems the tests share: PDDL domains and problems, their plans, and the
few builders that lay them out as tasks (each written once, here)."""

from __future__ import annotations

import functools
import itertools
from collections.abc import Sequence
from pathlib import Path

from evaluation.tracks import TRACKS
from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from twostep.pddl import Problem, parse_problem
from twostep.plans.simulate import GroundAction, Grounder


@functools.cache
def problem(domain: str, text: str) -> Problem:
    return parse_problem(domain, text)


def ground(prob: Problem, *plans: list[str]) -> list[list[GroundAction]]:
    grounder = Grounder(prob)
    return [grounder.ground_plan(plan) for plan in plans]


BLOCKSWORLD = """
(define (domain blocksworld)
 (:requirements :strips)
 (:predicates (clear ?x) (ontable ?x) (on ?x ?y) (arm-empty) (holding ?x))
 (:action pickup :parameters (?x)
  :precondition (and (clear ?x) (ontable ?x) (arm-empty))
  :effect (and (not (ontable ?x)) (not (clear ?x)) (not (arm-empty)) (holding ?x)))
 (:action putdown :parameters (?x)
  :precondition (holding ?x)
  :effect (and (not (holding ?x)) (clear ?x) (arm-empty) (ontable ?x)))
 (:action stack :parameters (?x ?y)
  :precondition (and (holding ?x) (clear ?y))
  :effect (and (not (holding ?x)) (not (clear ?y)) (clear ?x) (arm-empty) (on ?x ?y)))
 (:action unstack :parameters (?x ?y)
  :precondition (and (on ?x ?y) (clear ?x) (arm-empty))
  :effect (and (holding ?x) (clear ?y) (not (clear ?x)) (not (arm-empty)) (not (on ?x ?y)))))
"""


TOY = """
(define (domain toy)
 (:requirements :strips :negative-preconditions)
 (:predicates (f ?x) (g ?x) (h ?x))
 (:action set :parameters (?x) :effect (f ?x))
 (:action unset :parameters (?x) :precondition (f ?x) :effect (not (f ?x)))
 (:action grab :parameters (?x) :precondition (f ?x) :effect (and (not (f ?x)) (h ?x)))
 (:action drop :parameters (?x) :precondition (h ?x) :effect (and (not (h ?x)) (f ?x)))
 (:action mark :parameters (?x) :precondition (f ?x) :effect (g ?x))
 (:action avoid :parameters (?x) :precondition (not (f ?x)) :effect (g ?x))
 (:action erase :parameters (?x) :precondition (g ?x) :effect (not (g ?x))))
"""


TOY_AGENT = ("h",)


TOY_PROBLEM = "(define (problem toy-1) (:domain toy) (:objects o1 o2) (:init) (:goal (and)))"


def tracks_problem(
    lengths: Sequence[int], hub_at: int | None = None
) -> tuple[str, list[list[str]]]:
    """Carts on private tracks of the given lengths, optionally all crossing one hub cell.

    Returns the problem text and each cart's plan (drive to the end of its track).
    """
    cells: list[str] = []
    init = ["(ready)"]
    goal = []
    plans = []
    for cart, length in enumerate(lengths):
        track = [f"k{cart}-{i}" for i in range(length + 1)]
        if hub_at is not None and 0 < hub_at < length:
            track[hub_at] = "hub"
        cells += [c for c in track if c not in cells]
        init.append(f"(at c{cart} {track[0]})")
        init += [f"(next {p} {q})" for p, q in itertools.pairwise(track)]
        init += [f"(free {c})" for c in track[1:] if c != "hub"]
        goal.append(f"(at c{cart} {track[-1]})")
        plans.append([f"(move c{cart} {p} {q})" for p, q in itertools.pairwise(track)])
    if hub_at is not None:
        init.append("(free hub)")
    carts = " ".join(f"c{i}" for i in range(len(lengths)))
    text = (
        f"(define (problem tracks-1) (:domain tracks)\n (:objects {carts} - cart "
        f"{' '.join(cells)} - cell)\n (:init {' '.join(sorted(set(init)))})\n"
        f" (:goal (and {' '.join(goal)})))"
    )
    return text, plans


STAGGERED = [(3, 8), (4, 11), (6, 10)] * 2  # three kinds of cart, two of each


def two_hub_tracks(hubs: list[tuple[int, int]], length: int):
    text, plans = two_hub_tracks_text(hubs, length)
    prob = problem(TRACKS, text)
    return prob, ground(prob, *plans)


def two_hub_tracks_text(hubs: list[tuple[int, int]], length: int) -> tuple[str, list[list[str]]]:
    """Carts on private tracks of ``length`` moves; cart c crosses the shared cells ``hub``
    at position hubs[c][0] and ``hub2`` at hubs[c][1] (the bench's staggered case).
    Returns the problem text (domain TRACKS) and each cart's plan."""
    cells, init, goal, plans = [], ["(ready)", "(free hub)", "(free hub2)"], [], []
    for cart, (first, second) in enumerate(hubs):
        track = [f"k{cart}-{i}" for i in range(length + 1)]
        track[first], track[second] = "hub", "hub2"
        cells += [c for c in track if c not in cells]
        init.append(f"(at c{cart} {track[0]})")
        init += [f"(next {p} {q})" for p, q in itertools.pairwise(track)]
        init += [f"(free {c})" for c in track[1:] if not c.startswith("hub")]
        goal.append(f"(at c{cart} {track[-1]})")
        plans.append([f"(move c{cart} {p} {q})" for p, q in itertools.pairwise(track)])
    carts = " ".join(f"c{i}" for i in range(len(hubs)))
    text = (
        f"(define (problem two-hubs) (:domain tracks) (:objects {carts} - cart "
        f"{' '.join(cells)} - cell) (:init {' '.join(sorted(set(init)))}) "
        f"(:goal (and {' '.join(goal)})))"
    )
    return text, plans


# reach: the nodes reachable from the source through open edges (recursive, layer 0);
# cut-off: the nodes not reachable (negation of a derived predicate: a higher layer).
GRAPH = """
(define (domain graph)
 (:requirements :strips :derived-predicates :negative-preconditions)
 (:predicates (edge ?a ?b) (open ?a ?b) (source ?a) (reach ?a) (cut-off ?a)
              (visited ?a) (lost ?a))
 (:derived (reach ?a) (source ?a))
 (:derived (reach ?b) (exists (?a) (and (reach ?a) (edge ?a ?b) (open ?a ?b))))
 (:derived (cut-off ?a) (not (reach ?a)))
 (:action close :parameters (?a ?b) :precondition (open ?a ?b) :effect (not (open ?a ?b)))
 (:action open-gate :parameters (?a ?b) :precondition (and (edge ?a ?b) (not (open ?a ?b)))
   :effect (open ?a ?b))
 (:action visit :parameters (?a) :precondition (reach ?a) :effect (visited ?a))
 (:action mark-lost :parameters (?a) :precondition (cut-off ?a) :effect (lost ?a)))
"""


GRAPH_PROBLEM = """
(define (problem graph-1) (:domain graph) (:objects n1 n2 n3 n4)
 (:init (source n1) (edge n1 n2) (edge n2 n3) (edge n3 n4) (open n1 n2) (open n2 n3))
 (:goal (and (visited n4) (lost n3))))
"""


# Costs computed from a static function, as IPC 2008's elevators and transport do.
ROAD_LENGTHS = """
(define (domain roads)
 (:requirements :typing :action-costs)
 (:types place)
 (:predicates (at ?p - place) (road ?a ?b - place))
 (:functions (road-length ?a ?b - place) - number (total-cost) - number)
 (:action drive :parameters (?a ?b - place)
   :precondition (and (at ?a) (road ?a ?b))
   :effect (and (not (at ?a)) (at ?b) (increase (total-cost) (road-length ?a ?b)))))
"""


ROAD_LENGTHS_PROBLEM = """
(define (problem roads-1) (:domain roads) (:objects a b c d - place)
 (:init (at a) (road a b) (road b d) (road a c) (road c d) (road a d)
   (= (road-length a b) 5) (= (road-length b d) 5) (= (road-length a c) 2)
   (= (road-length c d) 9) (= (road-length a d) 20) (= (total-cost) 0))
 (:goal (at d))
 (:metric minimize (total-cost)))
"""


DRIVE_OR_FLY = """
(define (domain roads)
 (:requirements :strips :typing :action-costs)
 (:types place)
 (:predicates (at ?p - place) (road ?a ?b - place))
 (:functions (total-cost) - number)
 (:action drive :parameters (?a ?b - place)
  :precondition (and (at ?a) (road ?a ?b))
  :effect (and (not (at ?a)) (at ?b) (increase (total-cost) 5)))
 (:action fly :parameters (?a ?b - place)
  :precondition (at ?a)
  :effect (and (not (at ?a)) (at ?b) (increase (total-cost) 12))))
"""


DRIVE_OR_FLY_PROBLEM = """
(define (problem trip) (:domain roads) (:objects a b c d - place)
 (:init (at a) (road a b) (road b c) (road c d) (= (total-cost) 0))
 (:goal (at d)) (:metric minimize (total-cost)))
"""


ROAD_COSTS = {"drive": 5, "fly": 12}


# An agent-specific predicate inside a quantifier, a conditional effect and a derived
# predicate: (busy) holds while the agent holds anything, so one hand holds one object.
SHELF = """
(define (domain shelf)
 (:requirements :adl :derived-predicates)
 (:predicates (holding ?o) (on-shelf ?o) (in-bin ?o) (busy))
 (:derived (busy) (exists (?o) (holding ?o)))
 (:action take :parameters (?o) :precondition (and (on-shelf ?o) (not (busy)))
   :effect (and (holding ?o) (not (on-shelf ?o))))
 (:action bin :parameters (?o) :precondition (holding ?o)
   :effect (and (in-bin ?o) (not (holding ?o))))
 (:action drop-all :parameters ()
   :effect (forall (?o) (when (holding ?o) (and (not (holding ?o)) (on-shelf ?o))))))
"""


SHELF_PROBLEM = """
(define (problem shelf-1) (:domain shelf) (:objects a b c)
 (:init (on-shelf a) (on-shelf b) (on-shelf c))
 (:goal (and (in-bin a) (in-bin b))))
"""


# Storage with four crates (our own problem for the sample's domain, whose own p01 has a
# single crate: three actions in a chain, nothing to deal): six depot areas in two rows,
# four container areas, one load area joining both; the hoist starts in the depot.
STORAGE_PROBLEM = """(define (problem storage-four-crates)
  (:domain Storage-Propositional)
  (:objects depot0-1-1 depot0-1-2 depot0-1-3 depot0-2-1 depot0-2-2 depot0-2-3
            container-0-0 container-0-1 container-0-2 container-0-3 - storearea
            hoist0 - hoist crate0 crate1 crate2 crate3 - crate
            container0 - container depot0 - depot loadarea - transitarea)
  (:init %s)
  (:goal (and (in crate0 depot0) (in crate1 depot0) (in crate2 depot0) (in crate3 depot0))))"""


def storage_init() -> str:
    depot = [f"depot0-{r}-{c}" for r in (1, 2) for c in (1, 2, 3)]
    facts = [f"(in {a} depot0)" for a in depot] + [f"(clear {a})" for a in depot[1:]]
    for a, b in [(0, 1), (1, 2), (3, 4), (4, 5), (0, 3), (1, 4), (2, 5)]:
        facts += [f"(connected {depot[a]} {depot[b]})", f"(connected {depot[b]} {depot[a]})"]
    for area in ("depot0-1-1", "depot0-1-3", *(f"container-0-{k}" for k in range(4))):
        facts += [f"(connected {area} loadarea)", f"(connected loadarea {area})"]
    for k in range(4):
        facts += [f"(in container-0-{k} container0)", f"(on crate{k} container-0-{k})",
                  f"(in crate{k} container0)"]  # fmt: skip
    return " ".join([*facts, "(at hoist0 depot0-1-1)", "(available hoist0)"])


BW = ["arm-empty", "holding"]


TERMES = ["at", "has-block"]


# c on a, d on b; goal: the single tower a-b-c-d
TALL_TOWER = blocks_problem(
    "(on c a) (on d b) (on-table a) (on-table b) (clear c) (clear d) (arm-empty)",
    "(on a b) (on b c) (on c d)",
)


TALL_TOWER_PLAN = (
    "(unstack c a)", "(putdown c)", "(unstack d b)", "(putdown d)",
    "(pickup c)", "(stack c d)", "(pickup b)", "(stack b c)", "(pickup a)", "(stack a b)",
)  # fmt: skip


TERMES_PLAN = (
    "(create-block d)", "(move d p3 n0)", "(place-block p3 p2 n0 n1)",  # the base, from p3
    "(move p3 d n0)", "(create-block d)", "(place-block d p1 n0 n1)",  # the ramp on p1
    "(create-block d)", "(move-up d n0 p1 n1)", "(place-block p1 p2 n1 n2)",  # the top
    "(move-down p1 n1 d n0)", "(remove-block d p1 n1 n0)", "(destroy-block d)",  # ramp away
)  # fmt: skip


# a depot d next to p1 and p3; p1 - p2 - p3 in a row; goal: a tower of height 2 on p2
TERMES_TOWER = """(define (problem tower) (:domain termes)
  (:objects n0 n1 n2 - numb d p1 p2 p3 - position)
  (:init (height d n0) (height p1 n0) (height p2 n0) (height p3 n0) (at d) (is-depot d)
    (succ n1 n0) (succ n2 n1)
    (neighbor d p1) (neighbor p1 d) (neighbor d p3) (neighbor p3 d)
    (neighbor p1 p2) (neighbor p2 p1) (neighbor p2 p3) (neighbor p3 p2))
  (:goal (and (height p2 n2) (height p1 n0) (height p3 n0) (not (has-block)))))"""


TWO_TOWERS = blocks_problem(
    " ".join(f"(on-table {b}) (clear {b})" for b in "abcdef") + " (arm-empty)",
    "(on a b) (on b c) (on d e) (on e f)",
    "a b c d e f",
)


TWO_TOWERS_PLAN = (
    "(pickup b)", "(stack b c)", "(pickup a)", "(stack a b)",
    "(pickup e)", "(stack e f)", "(pickup d)", "(stack d e)",
)  # fmt: skip


CUPS = ["hand-free", "holding"]


# A bar: each cup is taken from the shelf into the agent's hand, filled, served to one
# guest, washed to be filled again, put back. The agent's hand is its own.
CUPS_DOMAIN = """(define (domain cups)
  (:requirements :strips)
  (:predicates (hand-free) (holding ?c) (shelf ?c) (clean ?c) (full ?c) (used ?c)
    (thirsty ?g) (served ?g))
  (:action take :parameters (?c)
    :precondition (and (shelf ?c) (hand-free))
    :effect (and (holding ?c) (not (shelf ?c)) (not (hand-free))))
  (:action fill :parameters (?c)
    :precondition (and (holding ?c) (clean ?c))
    :effect (and (full ?c) (not (clean ?c))))
  (:action serve :parameters (?c ?g)
    :precondition (and (holding ?c) (full ?c) (thirsty ?g))
    :effect (and (served ?g) (used ?c) (not (full ?c)) (not (thirsty ?g))))
  (:action wash :parameters (?c)
    :precondition (and (holding ?c) (used ?c))
    :effect (and (clean ?c) (not (used ?c))))
  (:action put :parameters (?c)
    :precondition (holding ?c)
    :effect (and (shelf ?c) (hand-free) (not (holding ?c)))))"""


# The SA plan serves every guest from cup c1, washing it in between (the one-glass chain)
CUPS_SA_PLAN = (
    "(take c1)", "(fill c1)", "(serve c1 g1)", "(wash c1)", "(fill c1)", "(serve c1 g2)",
    "(wash c1)", "(fill c1)", "(serve c1 g3)",
)  # fmt: skip


CUPS_TASK = """(define (problem three) (:domain cups)
  (:objects c1 c2 c3 g1 g2 g3)
  (:init (hand-free) (shelf c1) (shelf c2) (shelf c3) (clean c1) (clean c2) (clean c3)
    (thirsty g1) (thirsty g2) (thirsty g3))
  (:goal (and (served g1) (served g2) (served g3))))"""


def task_files(folder: Path, goal: str = "(on a b)") -> tuple[Path, Path]:
    domain, problem = folder / "domain.pddl", folder / "p01.pddl"
    domain.write_text(BLOCKS_DOMAIN)
    problem.write_text(
        blocks_problem("(on-table a) (on-table b) (clear a) (clear b) (arm-empty)", goal, "a b")
    )
    return domain, problem
