"""Plans compiled to bit sets: numbered facts, states as Python ints.

A joint step is then a few integer operations. Two encodings, one per kind of task:

- *STRIPS* (every action a precondition, adds and deletes; no axioms): only environment
  facts are numbered; each agent's private copy of the agent-specific facts changes only
  through its own actions, so its content is fixed by its plan index and is checked apart
  (:mod:`twostep.makespan.diagnosis`). This is the fast path of the search.
- *General* (conditional effects, precondition variants or derived facts): an agent's
  effect on its own facts may depend on the shared state, so the copies are numbered too,
  one bit per agent and agent-specific fact, and live in the state. Derived facts are
  numbered as well (per agent when they depend on an agent-specific fact) and the state
  is closed under the axioms after every step (:class:`CompiledAxioms`, which has the
  grounded model's :class:`~twostep.pddl.grounded.Axioms` evaluate each agent's view).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from twostep.pddl import Fact, Goal
from twostep.pddl.grounded import Axioms
from twostep.plans.simulate import GroundAction

Node = tuple[tuple[int, ...], int]
"""A search node: each agent's next plan index and the state."""

Effect = tuple[int, int, int, int]
"""A conditional effect as bit sets: (condition true, condition false, add, delete)."""


@dataclass(frozen=True)
class CompiledStep:
    """One plan step as bit sets: precondition, effects, and what interference needs.

    ``add``/``delete`` always happen, ``effects`` when their condition holds in the state
    before the step; ``alternatives`` are other ways to meet a disjunctive precondition
    (each with its own effects). ``conditions`` are the facts the outcome depends on beyond
    the precondition (effect conditions, alternatives, the facts derived preconditions come
    from). ``possible_add``/``possible_delete``: what it adds or deletes in some state.
    """

    pre_positive: int
    pre_negative: int
    add: int
    delete: int
    effects: tuple[Effect, ...] = ()
    alternatives: tuple[CompiledStep, ...] = ()
    conditions: int = 0
    possible_add: int = field(default=-1, compare=False)
    possible_delete: int = field(default=-1, compare=False)

    def __post_init__(self) -> None:
        add, delete = self.add, self.delete
        for _, _, a, d in self.effects:
            add |= a
            delete |= d
        conditions = self.conditions
        for other in self.alternatives:
            add |= other.possible_add
            delete |= other.possible_delete
            conditions |= other.pre_positive | other.pre_negative | other.conditions
        object.__setattr__(self, "possible_add", add)
        object.__setattr__(self, "possible_delete", delete)
        object.__setattr__(self, "conditions", conditions)

    @property
    def simple(self) -> bool:
        return not self.effects and not self.alternatives

    @property
    def reads(self) -> int:
        return self.pre_positive | self.pre_negative | self.conditions

    @property
    def writes(self) -> int:
        return self.possible_add | self.possible_delete

    @property
    def touched(self) -> int:
        return self.reads | self.writes

    def applicable(self, state: int) -> bool:
        if self.pre_positive & state == self.pre_positive and not self.pre_negative & state:
            return True
        return any(other.applicable(state) for other in self.alternatives)

    def effect(self, state: int) -> tuple[int, int]:
        """(add, delete) in ``state`` (the state before the step)."""
        chosen = self
        if self.alternatives and not (
            self.pre_positive & state == self.pre_positive and not self.pre_negative & state
        ):
            chosen = next((o for o in self.alternatives if o.applicable(state)), self)
        add, delete = chosen.add, chosen.delete
        for positive, negative, a, d in chosen.effects:
            if positive & state == positive and not negative & state:
                add |= a
                delete |= d
        return add, delete

    def interferes(self, other: CompiledStep) -> bool:
        """Whether the two steps may not share a time step (see :mod:`twostep.makespan`)."""
        clash = (
            self.possible_delete & (other.pre_positive | other.possible_add)
            | self.possible_add & (other.pre_negative | other.possible_delete)
            | other.possible_delete & self.pre_positive
            | other.possible_add & self.pre_negative
        )
        if self.conditions or other.conditions:
            clash |= self.writes & other.conditions | other.writes & self.conditions
        return bool(clash)


class CompiledAxioms:
    """The task's axioms on bit-set states.

    :class:`~twostep.pddl.grounded.Axioms` stays the one evaluator: :meth:`close` decodes
    each agent's view of a state (the shared facts and its own copy) into facts, closes it
    there, and encodes the derived facts back (an agent-specific derived fact into that
    agent's bit). States repeat during the search, so results are remembered.
    """

    def __init__(
        self,
        axioms: Axioms,
        views: Sequence[tuple[Sequence[tuple[int, Fact]], Mapping[Fact, int]]],
        derived: int,
    ):
        """``views``: per agent, its basic facts' (bit, fact) and its derived facts' bits."""
        self.axioms = axioms
        self.views = views
        self.derived = derived
        self._closed: dict[int, int] = {}

    def close(self, state: int) -> int:
        state &= ~self.derived
        known = self._closed.get(state)
        if known is not None:
            return known
        closed = state
        for visible, encode in self.views:
            facts = [fact for bit, fact in visible if state & bit]
            for fact in self.axioms.close(facts):
                closed |= encode.get(fact, 0)
        self._closed[state] = closed
        return closed


@dataclass(frozen=True)
class CompiledTask:
    steps: tuple[tuple[CompiledStep, ...], ...]
    reads_from: tuple[tuple[int, ...], ...]
    """``reads_from[i][k]``: facts that agent i's actions k.. read (0 when done)."""
    writes_from: tuple[tuple[int, ...], ...]
    """``writes_from[i][k]``: facts that agent i's actions k.. may add or delete (0 when done)."""
    initial: int
    goal_positive: int
    goal_negative: int
    all_facts: int
    """The bit set of every numbered fact."""
    axioms: CompiledAxioms | None = None
    simple: bool = True
    """The STRIPS encoding (agent copies apart, no conditional effects, no axioms)."""

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

    def successor(self, state: int, steps: Iterable[CompiledStep]) -> int:
        """The state after ``steps`` run together from ``state`` (non-interfering steps)."""
        delete = add = 0
        for step in steps:
            if step.simple:
                add |= step.add
                delete |= step.delete
            else:
                a, d = step.effect(state)
                add |= a
                delete |= d
        state = (state & ~delete) | add
        if self.axioms is not None:
            state = self.axioms.close(state)
        return state


def is_simple(plans: Sequence[Sequence[GroundAction]]) -> bool:
    """Whether the STRIPS encoding fits: no conditional effects, variants or axioms."""
    return all(a.is_strips and not a.axioms for plan in plans for a in plan)


def task_axioms(plans: Sequence[Sequence[GroundAction]]) -> Axioms | None:
    """The axioms of the task the plans' actions come from (None: none)."""
    return next((a.axioms for plan in plans for a in plan if a.axioms), None)


def compile_task(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> CompiledTask:
    if is_simple(plans):
        return _compile_strips(plans, init, goal, agent_predicates)
    return _compile_general(plans, init, goal, agent_predicates)


def _task(
    steps: Sequence[tuple[CompiledStep, ...]],
    initial: int,
    goal_positive: int,
    goal_negative: int,
    facts: int,
    axioms: CompiledAxioms | None = None,
) -> CompiledTask:
    """The task, with the suffix unions of what each plan reads and writes; the general
    encoding when there are axioms or any step is not STRIPS."""
    reads_from, writes_from = [], []
    for plan_steps in steps:
        reads = [0] * (len(plan_steps) + 1)
        writes = [0] * (len(plan_steps) + 1)
        for k in range(len(plan_steps) - 1, -1, -1):
            reads[k] = reads[k + 1] | plan_steps[k].reads
            writes[k] = writes[k + 1] | plan_steps[k].writes
        reads_from.append(tuple(reads))
        writes_from.append(tuple(writes))
    simple = axioms is None and all(step.simple for plan in steps for step in plan)
    return CompiledTask(
        tuple(steps),
        tuple(reads_from),
        tuple(writes_from),
        initial,
        goal_positive,
        goal_negative,
        (1 << facts) - 1,
        axioms,
        simple,
    )


def _compile_strips(
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
    goal_positive = mask(goal.positive | goal.formula_facts)
    goal_negative = mask(goal.negative)
    # Facts no action or goal mentions never matter; leaving them out keeps states small.
    initial = sum(bit for fact, bit in bits.items() if fact in init)
    return _task(steps, initial, goal_positive, goal_negative, len(bits))


def _compile_general(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    agent_predicates: Collection[str],
) -> CompiledTask:
    axioms = task_axioms(plans)
    derived = axioms.derived if axioms is not None else frozenset()

    def agent_specific(fact: Fact) -> bool:
        if fact in derived and axioms is not None:
            return any(f[0] in agent_predicates for f in axioms.support(fact))
        return fact[0] in agent_predicates

    agents = max(len(plans), 1)
    bits: dict[tuple[int, Fact], int] = {}

    def bit_of(fact: Fact, agent: int) -> int:
        key = (agent if agent_specific(fact) else -1, fact)
        bit = bits.get(key)
        if bit is None:
            bit = bits[key] = 1 << len(bits)
        return bit

    def mask(facts: Iterable[Fact], agent: int) -> int:
        value = 0
        for fact in facts:
            value |= bit_of(fact, agent)
        return value

    def every_agent(facts: Iterable[Fact]) -> int:
        value = 0
        for fact in facts:
            for agent in range(agents):
                value |= bit_of(fact, agent)
        return value

    def support(facts: Iterable[Fact]) -> frozenset[Fact]:
        if axioms is None:
            return frozenset()
        return frozenset(s for f in facts if f in derived for s in axioms.support(f))

    def compile_action(action: GroundAction, agent: int) -> CompiledStep:
        effects = tuple(
            (
                mask(e.condition_positive, agent),
                mask(e.condition_negative, agent),
                mask(e.add, agent),
                mask(e.delete, agent),
            )
            for e in action.effects
        )
        read = action.pre_positive | action.pre_negative
        conditions = 0
        for e in action.effects:
            read |= e.condition
        for positive, negative, _, _ in effects:
            conditions |= positive | negative
        return CompiledStep(
            mask(action.pre_positive, agent),
            mask(action.pre_negative, agent),
            mask(action.add, agent),
            mask(action.delete, agent),
            effects,
            tuple(compile_action(other, agent) for other in action.alternatives),
            conditions | mask(support(read), agent),
        )

    steps = []
    for agent, plan in enumerate(plans):
        compiled: dict[int, CompiledStep] = {}
        agent_steps = []
        for action in plan:
            step = compiled.get(id(action))
            if step is None:
                step = compiled[id(action)] = compile_action(action, agent)
            agent_steps.append(step)
        steps.append(tuple(agent_steps))
    goal_positive = every_agent(goal.positive | goal.formula_facts)
    goal_negative = every_agent(goal.negative)
    # Every basic fact of the initial state is numbered: a derived fact may depend on
    # facts no action mentions (they keep their initial value).
    for fact in init:
        if fact not in derived:
            for agent in range(agents):
                bit_of(fact, agent)
    initial = sum(bit for (_, fact), bit in bits.items() if fact in init and fact not in derived)
    compiled_axioms = None
    if axioms:
        views = []
        owners = range(agents) if any(owner >= 0 for owner, _ in bits) else range(1)
        for agent in owners:
            mine = [
                (owner, fact, bit) for (owner, fact), bit in bits.items() if owner in (-1, agent)
            ]
            visible = [(bit, fact) for _, fact, bit in mine if fact not in derived]
            encode = {fact: bit for _, fact, bit in mine if fact in derived}
            views.append((visible, encode))
        derived_bits = sum(bit for (_, fact), bit in bits.items() if fact in derived)
        compiled_axioms = CompiledAxioms(axioms, views, derived_bits)
        initial = compiled_axioms.close(initial)
    return _task(steps, initial, goal_positive, goal_negative, len(bits), compiled_axioms)
