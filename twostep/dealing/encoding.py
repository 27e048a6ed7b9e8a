"""Facts as bits for plan-deal: a state of N agents is an environment int and one int per
agent, so applying an action, comparing states and testing the goal are a few integer
operations (the dealing steps simulate the same few hundred actions thousands of times).

Environment facts and an agent's own facts are numbered apart: every agent's copy of its
facts uses the same numbers, in its own int. :class:`FactSpace` numbers facts as it meets
them and is where plan-deal turns a :class:`~twostep.plans.simulate.GroundAction`'s sets into bits
(:mod:`~twostep.dealing.walks` reads them too, to pick the task's moves).

Only basic facts are bits. A STRIPS action that reads no derived fact is *exact* as bits:
its precondition, adds and deletes. Any other action (conditional effects, precondition
alternatives, a derived fact read) and a goal that reads derived facts are evaluated by
the grounded model itself, on the agent's view: the environment and its own facts,
closed under the task's axioms (:meth:`FactSpace.view`). Their masks then say what they
may read (``pre`` and ``neg`` alike) and may add or delete: the interference rule and the
shortcuts of the clean-up only need that much.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass, field

from twostep.pddl import Fact, Problem
from twostep.plans.simulate import GroundAction

Owns = tuple[int, ...]
"""Per agent: the bits of its own facts."""


@dataclass(frozen=True, eq=False, slots=True)
class Step:
    """One ground action as bits: what it needs, forbids, adds and deletes, in the
    environment and in the acting agent's own facts (``exact``; else what it may read, add
    and delete, and ``space`` evaluates it: module docstring)."""

    action: GroundAction
    pre_env: int
    neg_env: int
    add_env: int
    del_env: int
    pre_own: int
    neg_own: int
    add_own: int
    del_own: int
    space: FactSpace | None = field(default=None, repr=False)
    """None when the bits are exact; else the space that evaluates the action."""

    def __str__(self) -> str:
        return str(self.action)

    @property
    def exact(self) -> bool:
        return self.space is None

    def applicable(self, env: int, own: int) -> bool:
        if self.space is not None:
            return self.action.applicable(self.space.view(env, own))
        return (
            env & self.pre_env == self.pre_env
            and own & self.pre_own == self.pre_own
            and not (env & self.neg_env or own & self.neg_own)
        )

    def apply(self, env: int, own: int) -> tuple[int, int]:
        """The successor (delete before add, as in PDDL)."""
        if self.space is not None:
            return self.space.bits(self.action.apply(self.space.view(env, own)))
        return (env & ~self.del_env) | self.add_env, (own & ~self.del_own) | self.add_own

    @property
    def writes_env(self) -> int:
        return self.add_env | self.del_env

    @property
    def touches_env(self) -> int:
        return self.pre_env | self.neg_env | self.add_env | self.del_env


@dataclass(frozen=True, slots=True)
class GoalBits:
    """A goal as bits: environment literals once, agent literals in every agent's copy.
    A goal that reads derived facts is checked by the problem on every agent's view, and
    its bits are its basic environment literals alone (those the clean-up's shortcut may
    rely on)."""

    pos_env: int
    neg_env: int
    pos_own: int
    neg_own: int
    space: FactSpace | None = None
    """None when the bits are the whole goal; else the space whose problem checks it."""

    def holds(self, env: int, owns: Iterable[int]) -> bool:
        if env & self.pos_env != self.pos_env or env & self.neg_env:
            return False
        if self.space is not None:
            goal, view = self.space.problem.goal, self.space.view
            return all(goal.holds(view(env, own)) for own in owns)
        return all(self.own_holds(own) for own in owns)

    def own_holds(self, own: int) -> bool:
        """Whether one agent's copy meets the goal's agent literals."""
        return own & self.pos_own == self.pos_own and not own & self.neg_own

    def env_met(self, env: int) -> int:
        """The bits of the goal's environment literals that hold in ``env``."""
        return env & self.pos_env | ~env & self.neg_env


VIEWS_KEPT = 200_000
"""Agent views :meth:`FactSpace.view` remembers before it starts again."""


class FactSpace:
    """The numbering of one task's basic facts (module docstring), and its actions as
    steps."""

    def __init__(
        self,
        problem: Problem,
        agent_predicates: Collection[str],
        positional: Collection[str],
        harmless: Collection[str] = (),
    ) -> None:
        self.problem = problem
        axioms = problem.grounded.axioms
        self.derived: frozenset[Fact] = axioms.derived if axioms else frozenset()
        self._views: dict[tuple[int, int], frozenset[Fact]] = {}
        self.agent_predicates = frozenset(agent_predicates)
        self.positional = frozenset(positional)
        self.harmless = frozenset(harmless)
        self.where = 0
        """The own bits that say where an agent stands (positional predicates)."""
        self.where_env = 0
        """The environment bits of positional predicates (``clear`` where hoists move)."""
        self.harmless_env = 0
        """The environment bits of ``harmless`` predicates (facts only ever added, such as
        a cell ``visited``: more of them never stops an action)."""
        self._env: dict[Fact, int] = {}
        self._own: dict[Fact, int] = {}
        self._own_facts: list[Fact] = []
        self._env_facts: list[Fact] = []
        self._steps: dict[GroundAction, Step] = {}

    def bits(self, facts: Iterable[Fact]) -> tuple[int, int]:
        """The environment bits and the own bits of the basic facts among ``facts``."""
        env = own = 0
        derived = self.derived
        for fact in facts:
            if fact in derived:
                continue
            if fact[0] in self.agent_predicates:
                bit = self._own.get(fact)
                if bit is None:
                    bit = self._own[fact] = 1 << len(self._own)
                    self._own_facts.append(fact)
                    if fact[0] in self.positional:
                        self.where |= bit
                own |= bit
            else:
                bit = self._env.get(fact)
                if bit is None:
                    bit = self._env[fact] = 1 << len(self._env)
                    self._env_facts.append(fact)
                    if fact[0] in self.positional:
                        self.where_env |= bit
                    if fact[0] in self.harmless:
                        self.harmless_env |= bit
                env |= bit
        return env, own

    def view(self, env: int, own: int) -> frozenset[Fact]:
        """An agent's state as facts: the environment, its own facts, and what the axioms
        derive from them."""
        key = (env, own)
        found = self._views.get(key)
        if found is None:
            facts = [f for k, f in enumerate(self._env_facts) if env >> k & 1]
            facts += [f for k, f in enumerate(self._own_facts) if own >> k & 1]
            if len(self._views) >= VIEWS_KEPT:
                self._views.clear()
            found = self._views[key] = self.problem.close(facts)
        return found

    def step(self, action: GroundAction) -> Step:
        found = self._steps.get(action)
        if found is None:
            exact = action.is_strips and not (
                self.derived & (action.pre_positive | action.pre_negative)
            )
            if exact:
                pre_env, pre_own = self.bits(action.pre_positive)
                neg_env, neg_own = self.bits(action.pre_negative)
            else:  # whatever it may read, as a need and as a thing forbidden
                pre_env, pre_own = neg_env, neg_own = self.bits(action.reads)
            add_env, add_own = self.bits(action.possible_add)
            del_env, del_own = self.bits(action.possible_delete)
            found = Step(action, pre_env, neg_env, add_env, del_env, pre_own, neg_own,
                         add_own, del_own, None if exact else self)  # fmt: skip
            self._steps[action] = found
        return found

    def steps(self, actions: Sequence[GroundAction]) -> list[Step]:
        return [self.step(a) for a in actions]

    def goal(self) -> GoalBits:
        """The problem's goal as bits."""
        goal = self.problem.goal
        pos_env, pos_own = self.bits(goal.positive)
        neg_env, neg_own = self.bits(goal.negative)
        literals = goal.positive | goal.negative | goal.formula_facts
        if goal.formula is not None or literals & self.derived:
            return GoalBits(pos_env, neg_env, 0, 0, self)
        return GoalBits(pos_env, neg_env, pos_own, neg_own)

    def own_facts(self, own: int) -> frozenset[Fact]:
        """The own facts whose bits are set in ``own``."""
        return frozenset(f for k, f in enumerate(self._own_facts) if own >> k & 1)
