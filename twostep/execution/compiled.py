"""Plans compiled to bit sets: numbered environment facts, states as Python ints.

A joint step is then a few integer operations; agent-specific facts are left out (each
agent's copy is checked apart, in :mod:`twostep.execution.diagnosis`).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass

from twostep.pddl import Fact, Goal
from twostep.strips import GroundAction

Node = tuple[tuple[int, ...], int]
"""A search node: each agent's next plan index and the environment state."""


@dataclass(frozen=True)
class CompiledStep:
    """The environment part of one plan step, as bit sets over numbered facts."""

    pre_positive: int
    pre_negative: int
    add: int
    delete: int

    @property
    def reads(self) -> int:
        return self.pre_positive | self.pre_negative

    @property
    def writes(self) -> int:
        return self.add | self.delete

    @property
    def touched(self) -> int:
        return self.reads | self.writes

    def applicable(self, state: int) -> bool:
        return self.pre_positive & state == self.pre_positive and not self.pre_negative & state

    def interferes(self, other: CompiledStep) -> bool:
        return bool(
            self.delete & (other.pre_positive | other.add)
            | self.add & (other.pre_negative | other.delete)
            | other.delete & self.pre_positive
            | other.add & self.pre_negative
        )


@dataclass(frozen=True)
class CompiledTask:
    steps: tuple[tuple[CompiledStep, ...], ...]
    reads_from: tuple[tuple[int, ...], ...]
    """reads_from[i][k]: facts that agent i's actions k.. read (0 when done)."""
    writes_from: tuple[tuple[int, ...], ...]
    """writes_from[i][k]: facts that agent i's actions k.. add or delete (0 when done)."""
    initial: int
    goal_positive: int
    goal_negative: int
    all_facts: int
    """The bit set of every numbered fact."""

    @property
    def lengths(self) -> tuple[int, ...]:
        return tuple(len(plan) for plan in self.steps)

    @property
    def touched(self) -> tuple[int, ...]:
        """touched[i]: the facts agent i's plan reads or writes anywhere."""
        return tuple(
            reads[0] | writes[0]
            for reads, writes in zip(self.reads_from, self.writes_from, strict=True)
        )


def compile_task(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> CompiledTask:
    bits: dict[Fact, int] = {}

    def mask(facts: Iterable[Fact]) -> int:
        value = 0
        for fact in facts:
            if fact[0] in agent_predicates:
                continue
            bit = bits.get(fact)
            if bit is None:
                bit = bits[fact] = 1 << len(bits)
            value |= bit
        return value

    compiled: dict[int, CompiledStep] = {}
    steps = []
    for plan in plans:
        agent_steps = []
        for action in plan:
            step = compiled.get(id(action))
            if step is None:
                step = compiled[id(action)] = CompiledStep(
                    mask(action.pre_positive),
                    mask(action.pre_negative),
                    mask(action.add),
                    mask(action.delete),
                )
            agent_steps.append(step)
        steps.append(tuple(agent_steps))
    goal_positive, goal_negative = mask(goal.positive), mask(goal.negative)
    # Facts no action or goal mentions never matter; leaving them out keeps states small.
    initial = sum(bit for fact, bit in bits.items() if fact in init)
    reads_from, writes_from = [], []
    for plan_steps in steps:
        reads = [0] * (len(plan_steps) + 1)
        writes = [0] * (len(plan_steps) + 1)
        for k in range(len(plan_steps) - 1, -1, -1):
            reads[k] = reads[k + 1] | plan_steps[k].reads
            writes[k] = writes[k + 1] | plan_steps[k].writes
        reads_from.append(tuple(reads))
        writes_from.append(tuple(writes))
    return CompiledTask(
        tuple(steps),
        tuple(reads_from),
        tuple(writes_from),
        initial,
        goal_positive,
        goal_negative,
        (1 << len(bits)) - 1,
    )
