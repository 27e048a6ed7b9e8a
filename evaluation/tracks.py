"""The tracks problems the parallel-execution scorer is measured and tested on: carts on
private tracks of a given length, each agent's plan driving its cart to the end, crossing
shared cells (a hub) where a case says so. :func:`build` lays a case out as a single-agent
problem (domain :data:`TRACKS`), its N-agent twin (:data:`TRACKS_MA`, for
unified-planning's simulator) and the plans. Used by ``bench/bench_execution.py``,
``bench/bench_score_cli.py`` and ``tests/examples.py``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

AGENTS = 4
PLAN_LENGTH = 60

TRACKS = """
(define (domain tracks)
 (:requirements :strips :typing)
 (:types cart cell)
 (:predicates (at ?c - cart ?p - cell) (next ?p - cell ?q - cell) (free ?p - cell) (ready))
 (:action move :parameters (?c - cart ?p - cell ?q - cell)
  :precondition (and (ready) (at ?c ?p) (next ?p ?q) (free ?q))
  :effect (and (not (at ?c ?p)) (not (free ?q)) (at ?c ?q) (free ?p))))
"""

TRACKS_MA = """
(define (domain tracks-ma)
 (:requirements :strips :typing)
 (:types agent cart cell)
 (:predicates (at ?c - cart ?p - cell) (next ?p - cell ?q - cell) (free ?p - cell)
              (ready ?a - agent))
 (:action move :parameters (?a - agent ?c - cart ?p - cell ?q - cell)
  :precondition (and (ready ?a) (at ?c ?p) (next ?p ?q) (free ?q))
  :effect (and (not (at ?c ?p)) (not (free ?q)) (at ?c ?q) (free ?p))))
"""

AGENT_PREDICATES = ("ready",)


@dataclass(frozen=True)
class Case:
    name: str
    shared_cells: dict[str, dict[int, float]]
    """Shared cell -> {cart: position as a fraction of the track}."""


CASES = (
    Case("independent", {}),
    Case(
        "shared",
        {
            "hub": {0: 1 / 3, 1: 1 / 3, 2: 1 / 3, 3: 1 / 3},
            "x01": {0: 2 / 3, 1: 2 / 3},
            "x23": {2: 3 / 4, 3: 3 / 4},
        },
    ),
)


def shared_case(agents: int) -> Case:
    """The ``shared`` case for any N: every track crosses the hub a third of the way,
    and carts 2p, 2p+1 share a crossing at 2/3 (p even) or 3/4 (p odd) of their tracks."""
    cells: dict[str, dict[int, float]] = {"hub": dict.fromkeys(range(agents), 1 / 3)}
    for first in range(0, agents - 1, 2):
        at = 2 / 3 if first % 4 == 0 else 3 / 4
        cells[f"x{first}{first + 1}"] = {first: at, first + 1: at}
    return Case("shared", cells)


@dataclass(frozen=True)
class Instance:
    single_agent_problem: str
    multi_agent_problem: str
    plans: list[list[str]]


def build(case: Case, length: int, agents: int = AGENTS) -> Instance:
    """Tracks of ``length`` moves per cart; each agent's plan drives its cart to the end."""
    cells: list[str] = []
    facts: list[str] = []
    goal: list[str] = []
    plans: list[list[str]] = []
    for cart in range(agents):
        track = [f"k{cart}-{i}" for i in range(length + 1)]
        for cell, positions in case.shared_cells.items():
            if cart in positions:
                track[max(1, min(length - 1, round(positions[cart] * length)))] = cell
        cells += [c for c in track if c not in cells]
        facts.append(f"(at c{cart} {track[0]})")
        facts += [f"(next {p} {q})" for p, q in itertools.pairwise(track)]
        goal.append(f"(at c{cart} {track[-1]})")
        plans.append([f"(move c{cart} {p} {q})" for p, q in itertools.pairwise(track)])
    facts += [f"(free {c})" for c in cells if not c.endswith("-0")]
    carts = " ".join(f"c{i}" for i in range(agents))
    agent_names = " ".join(f"a{i}" for i in range(agents))
    body = " ".join(sorted(set(facts)))
    goal_text = f"(:goal (and {' '.join(goal)}))"
    single = (
        f"(define (problem tracks-{case.name}) (:domain tracks)\n"
        f" (:objects {carts} - cart {' '.join(cells)} - cell)\n"
        f" (:init (ready) {body})\n {goal_text})"
    )
    ready = " ".join(f"(ready a{i})" for i in range(agents))
    multi = (
        f"(define (problem tracks-{case.name}-ma) (:domain tracks-ma)\n"
        f" (:objects {agent_names} - agent {carts} - cart {' '.join(cells)} - cell)\n"
        f" (:init {ready} {body})\n {goal_text})"
    )
    return Instance(single, multi, plans)


def staggered_case(agents: int) -> Case:
    """Two shared cells every cart crosses, at positions that differ by cart, so carts
    reach them at different times and the greedy order is not always optimal."""
    return Case(
        "staggered",
        {
            "hub": {cart: (2 + cart % 3) / 8 for cart in range(agents)},
            "hub2": {cart: (5 + (2 * cart) % 3) / 8 for cart in range(agents)},
        },
    )
