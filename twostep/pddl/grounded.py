"""The grounded task: ground actions with conditional effects, axioms, and what a state is.

This is the one state model of the project. A *state* is a ``frozenset`` of facts
(:data:`Fact`: predicate and object names, lowercase) that is *closed*: it holds the basic
facts of the task and every derived fact the task's axioms derive from them. A state
built from a closed state by the model's own operations (:meth:`GroundAction.apply`,
:meth:`GroundTask.close`) is closed again; a state assembled by set surgery (the
environment part of one state joined to an agent's own facts) is closed with
:meth:`GroundTask.close` before anything is evaluated on it.

Where it comes from
    :mod:`twostep.pddl.sas` reads this model from Fast Downward's translator output, so it
    is exactly the task the planner grounds: the same operators (one per plan name, with
    every variant the translator made of it), the same effect conditions, the same
    action costs, the same axioms. Facts the translator leaves out because they never
    change (static facts) come from the problem's own initial state.

Actions (PDDL semantics)
    An action is applicable when its precondition holds. Its effects are evaluated in the
    state before it: the unconditional adds and deletes, and every conditional effect
    whose condition holds there. The successor deletes first and adds after, and is then
    closed under the axioms. One plan name may stand for several operators (the
    translator splits a disjunctive or existential precondition into variants): the
    action applies when any variant does, and takes the effects of the first variant
    that applies; the variants agree wherever they apply, since they differ only in how
    the precondition is met.

Possible effects (the interference rule's input)
    :attr:`GroundAction.possible_add` and :attr:`~GroundAction.possible_delete` are what
    the action adds or deletes in some state: its unconditional effects and the effects of
    every conditional effect, over all variants. :attr:`GroundAction.reads` is every fact
    the outcome of the action depends on: its preconditions, its effect conditions, and
    for a derived fact among them, every basic fact it is derived from. Two actions may
    share a time step only when neither possibly writes what the other reads, possibly
    deletes what the other needs or possibly adds, or possibly adds what the other needs
    false (see :mod:`twostep.makespan`): a conservative rule, exact for STRIPS actions.

Axioms (derived facts, evaluated as Fast Downward evaluates them)
    Derived facts are false by default. Rules come in layers; layer by layer, a rule
    whose conditions hold makes its head true, until nothing changes (a least fixpoint).
    A rule may require a derived fact of its own or a lower layer to be true, and a
    derived fact of a strictly lower layer to be false (negation as failure, settled
    before its layer starts): the stratified semantics of Fast Downward's axiom
    evaluator. :class:`Axioms` is the one owner of this evaluation.
"""

from __future__ import annotations

import functools
from collections import defaultdict
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace

Fact = tuple[str, ...]
"""A ground atom: predicate name followed by object names, all lowercase."""

State = frozenset[Fact]


def fact_to_pddl(fact: Fact) -> str:
    return "(" + " ".join(fact) + ")"


class PlanError(Exception):
    """A plan that names an unknown action or object, or cannot be applied."""


@dataclass(frozen=True)
class ConditionalEffect:
    """``(when condition effect)``, ground: adds and deletes that happen when the
    condition holds in the state before the action."""

    condition_positive: frozenset[Fact]
    condition_negative: frozenset[Fact]
    add: frozenset[Fact] = frozenset()
    delete: frozenset[Fact] = frozenset()

    def triggers(self, state: frozenset[Fact] | set[Fact]) -> bool:
        return self.condition_positive <= state and not (self.condition_negative & state)

    @property
    def condition(self) -> frozenset[Fact]:
        return self.condition_positive | self.condition_negative


@dataclass(frozen=True)
class AxiomRule:
    """``head`` becomes true when ``positive`` hold and ``negative`` do not (layer ``layer``)."""

    head: Fact
    positive: tuple[Fact, ...]
    negative: tuple[Fact, ...]
    layer: int


class Axioms:
    """A task's axiom rules: derived facts computed from basic ones (see the module doc)."""

    def __init__(self, rules: Sequence[AxiomRule], derived: Iterable[Fact] = ()):
        self.rules = tuple(rules)
        self.derived: frozenset[Fact] = frozenset(derived) | {r.head for r in self.rules}
        layers: dict[int, list[AxiomRule]] = defaultdict(list)
        for rule in self.rules:
            layers[rule.layer].append(rule)
        self._layers = [tuple(layers[k]) for k in sorted(layers)]
        self._support: dict[Fact, frozenset[Fact]] = {}

    def __bool__(self) -> bool:
        return bool(self.rules)

    def __getstate__(self) -> dict[str, object]:
        return {"rules": self.rules, "derived": self.derived}

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__init__(state["rules"], state["derived"])  # type: ignore[misc, arg-type]

    def close(self, facts: Iterable[Fact]) -> frozenset[Fact]:
        """The basic facts among ``facts`` and every derived fact that holds with them."""
        derived = self.derived
        state = {f for f in facts if f not in derived}
        for rules in self._layers:
            heads: list[Fact] = []
            # Horn propagation within the layer: a rule fires once its last missing
            # positive condition of this layer becomes true. Conditions on basic facts and
            # on lower layers are final here, so they are checked once.
            waiting: dict[Fact, list[int]] = defaultdict(list)
            missing_count: list[int] = []
            queue: list[Fact] = []
            for rule in rules:
                if any(f in state for f in rule.negative):
                    continue
                missing = [f for f in rule.positive if f not in state]
                if any(f not in derived for f in missing):
                    continue  # a basic condition that does not hold: never fires
                if not missing:
                    queue.append(rule.head)
                    continue
                for f in missing:
                    waiting[f].append(len(missing_count))
                missing_count.append(len(missing))
                heads.append(rule.head)
            while queue:
                head = queue.pop()
                if head in state:
                    continue
                state.add(head)
                for number in waiting.pop(head, ()):
                    missing_count[number] -= 1
                    if missing_count[number] == 0:
                        queue.append(heads[number])
        return frozenset(state)

    def support(self, fact: Fact) -> frozenset[Fact]:
        """The basic facts a derived ``fact`` depends on (through any rule, any depth);
        ``{fact}`` for a basic fact."""
        if fact not in self.derived:
            return frozenset((fact,))
        known = self._support.get(fact)
        if known is not None:
            return known
        heads = self.by_head
        found: set[Fact] = set()
        seen = {fact}
        stack = [fact]
        while stack:
            current = stack.pop()
            for rule in heads.get(current, ()):
                for body in (*rule.positive, *rule.negative):
                    if body in self.derived:
                        if body not in seen:
                            seen.add(body)
                            stack.append(body)
                    else:
                        found.add(body)
        result = self._support[fact] = frozenset(found)
        return result

    @functools.cached_property
    def by_head(self) -> dict[Fact, list[AxiomRule]]:
        heads: dict[Fact, list[AxiomRule]] = defaultdict(list)
        for rule in self.rules:
            heads[rule.head].append(rule)
        return dict(heads)


@dataclass(frozen=True)
class GroundAction:
    """One ground action: its plan name, precondition, effects and cost.

    ``add``/``delete`` are the effects that always happen, ``effects`` the conditional
    ones; ``alternatives`` are further operators of the same plan name (other ways to
    meet a disjunctive or existential precondition). ``axioms`` close every successor.
    """

    name: str
    args: tuple[str, ...]
    pre_positive: frozenset[Fact]
    pre_negative: frozenset[Fact]
    add: frozenset[Fact] = frozenset()
    delete: frozenset[Fact] = frozenset()
    effects: tuple[ConditionalEffect, ...] = ()
    cost: int = 1
    alternatives: tuple[GroundAction, ...] = ()
    axioms: Axioms | None = field(default=None, compare=False, repr=False)

    def __str__(self) -> str:
        return "(" + " ".join((self.name, *self.args)) + ")"

    def with_axioms(self, axioms: Axioms | None) -> GroundAction:
        """The same action, its successors closed under ``axioms``."""
        return replace(
            self,
            alternatives=tuple(a.with_axioms(axioms) for a in self.alternatives),
            axioms=axioms if axioms else None,
        )

    def _holds(self, state: frozenset[Fact] | set[Fact]) -> bool:
        return self.pre_positive <= state and not (self.pre_negative & state)

    def variant(self, state: frozenset[Fact] | set[Fact]) -> GroundAction | None:
        """The operator of this plan name that applies in ``state`` (None: none does)."""
        if self._holds(state):
            return self
        for other in self.alternatives:
            if other._holds(state):
                return other
        return None

    def applicable(self, state: frozenset[Fact] | set[Fact]) -> bool:
        return self.variant(state) is not None

    def failing_precondition(self, state: frozenset[Fact] | set[Fact]) -> str | None:
        """The first precondition that does not hold in ``state``, as PDDL, or None."""
        if self.applicable(state):
            return None
        for fact in sorted(self.pre_positive - state):
            return fact_to_pddl(fact)
        for fact in sorted(self.pre_negative & state):
            return f"(not {fact_to_pddl(fact)})"
        return "(one of its precondition's alternatives)"

    def effect_in(
        self, state: frozenset[Fact] | set[Fact]
    ) -> tuple[frozenset[Fact], frozenset[Fact]]:
        """(adds, deletes) of the action in ``state`` (the state before it)."""
        chosen = self.variant(state) or self
        if not chosen.effects:
            return chosen.add, chosen.delete
        add, delete = set(chosen.add), set(chosen.delete)
        for effect in chosen.effects:
            if effect.triggers(state):
                add |= effect.add
                delete |= effect.delete
        return frozenset(add), frozenset(delete)

    def apply(self, state: frozenset[Fact]) -> frozenset[Fact]:
        """The successor state: effects evaluated in ``state``, deletes before adds, closed
        under the axioms."""
        add, delete = self.effect_in(state)
        successor = (state - delete) | add
        if self.axioms:
            return self.axioms.close(successor)
        return successor

    @property
    def is_strips(self) -> bool:
        """No conditional effects and no alternatives: precondition, add, delete."""
        return not self.effects and not self.alternatives

    @functools.cached_property
    def possible_add(self) -> frozenset[Fact]:
        """Every fact the action adds in some state."""
        found = set(self.add)
        for effect in self.effects:
            found |= effect.add
        for other in self.alternatives:
            found |= other.possible_add
        return frozenset(found)

    @functools.cached_property
    def possible_delete(self) -> frozenset[Fact]:
        """Every fact the action deletes in some state."""
        found = set(self.delete)
        for effect in self.effects:
            found |= effect.delete
        for other in self.alternatives:
            found |= other.possible_delete
        return frozenset(found)

    @functools.cached_property
    def condition_facts(self) -> frozenset[Fact]:
        """Facts the action's outcome depends on beyond its precondition: effect
        conditions, the preconditions of its alternatives, and the basic facts its derived
        preconditions and conditions come from."""
        found: set[Fact] = set()
        for effect in self.effects:
            found |= effect.condition
        for other in self.alternatives:
            found |= other.pre_positive | other.pre_negative | other.condition_facts
        if self.axioms:
            derived = self.axioms.derived
            for fact in (*self.pre_positive, *self.pre_negative, *tuple(found)):
                if fact in derived:
                    found |= self.axioms.support(fact)
        return frozenset(found)

    @property
    def reads(self) -> frozenset[Fact]:
        """Every fact the action's applicability or outcome depends on."""
        return self.pre_positive | self.pre_negative | self.condition_facts

    @property
    def writes(self) -> frozenset[Fact]:
        return self.possible_add | self.possible_delete

    @property
    def facts(self) -> frozenset[Fact]:
        """Every fact the action reads or writes."""
        return self.reads | self.writes


@dataclass(frozen=True, eq=False)
class GroundTask:
    """The grounded task: actions by plan name, axioms, and the translator's goal."""

    actions: Mapping[str, GroundAction]
    """Plan name ``"(name a b)"`` -> the action."""
    axioms: Axioms
    goal_positive: frozenset[Fact] = frozenset()
    goal_negative: frozenset[Fact] = frozenset()
    """The goal as the translator grounds it (a complex goal: a derived fact)."""
    action_costs: bool = False
    """Whether the task minimises action costs (else every action costs 1)."""

    def close(self, facts: Iterable[Fact]) -> frozenset[Fact]:
        """``facts`` as a state: basic facts kept, derived facts evaluated."""
        if not self.axioms:
            return facts if isinstance(facts, frozenset) else frozenset(facts)
        return self.axioms.close(facts)

    def prune_axioms(self, goal: Iterable[Fact] = ()) -> GroundTask:
        """This task without the translator's own axiom rules (``@`` in their names) that
        no action, other rule, the translator's goal or the facts ``goal`` need (its
        empty-goal axiom, for one). The task's derived predicates all stay: a subgoal may
        name any of them."""
        if not self.axioms:
            return self
        derived = self.axioms.derived
        needed: set[Fact] = {f for f in derived if "@" not in f[0]}
        for action in self.actions.values():
            for variant in (action, *action.alternatives):
                facts = set(variant.pre_positive | variant.pre_negative)
                for effect in variant.effects:
                    facts |= effect.condition
                needed |= facts & derived
        needed |= (self.goal_positive | self.goal_negative | set(goal)) & derived
        by_head = self.axioms.by_head
        stack = list(needed)
        while stack:
            for rule in by_head.get(stack.pop(), ()):
                for body in (*rule.positive, *rule.negative):
                    if body in derived and body not in needed:
                        needed.add(body)
                        stack.append(body)
        kept = [rule for rule in self.axioms.rules if rule.head in needed]
        if len(kept) == len(self.axioms.rules):
            return self
        axioms = Axioms(kept, derived & needed)
        actions = {key: action.with_axioms(axioms) for key, action in self.actions.items()}
        return GroundTask(
            actions, axioms, self.goal_positive, self.goal_negative, self.action_costs
        )

    def action(self, text: str) -> GroundAction:
        """The action with plan name ``text`` (``(pickup b1)`` or ``pickup b1``)."""
        name, args = parse_action(text)
        key = "(" + " ".join((name, *args)) + ")"
        found = self.actions.get(key)
        if found is None:
            raise PlanError(
                f"{key} is not an action of this task (unknown name or object, wrong "
                "arguments, or never applicable from its initial state)"
            )
        return found


def parse_action(text: str) -> tuple[str, tuple[str, ...]]:
    """Split ``"(stack b1 b2)"`` (or ``"stack b1 b2"``) into name and arguments."""
    words = text.strip().strip("()").lower().split()
    if not words:
        raise PlanError(f"empty action {text!r}")
    return words[0], tuple(words[1:])
