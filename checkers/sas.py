"""Fast Downward's grounded task (``output.sas``, format version 3) and what a plan does in it.

Written apart from ``twostep``: it shares no code with the library and reads only the
translator's documented output format. The semantics are those of Fast Downward's search:

* an operator applies when its prevail conditions and the ``pre`` value of every effect
  (other than -1) hold;
* its effects fire when their own conditions hold in the state *before* the step; a fired
  effect sets its variable (effects are applied in file order);
* axioms: every derived variable first takes its default value (its value in the initial
  state), then layer by layer, lowest first, rules whose conditions hold set their variable,
  until nothing changes. A condition on a lower layer's default value is negation by
  failure (that layer is final when a higher one is computed);
* a plan costs the sum of its operators' costs when the task uses costs (``begin_metric 1``),
  else one per step; it is valid when every step applies and the goal holds at the end.

A step names a ground action as twostep and Fast Downward write it: ``(name arg ...)``.
Several operators can carry one name (the translator splits disjunctive preconditions and
existential witnesses into copies); a step applies when one of them does.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

Condition = tuple[int, int]  # (variable, value)

MAX_ORDERS_CHECKED = 6  # steps with more actions are checked pairwise (720 orders at 6)


class SASFormatError(ValueError):
    """The text is not a task in Fast Downward's translator output format (version 3)."""


@dataclass(frozen=True)
class Variable:
    name: str
    layer: int  # -1: a state variable; >= 0: a derived variable of that axiom layer
    values: tuple[str, ...]

    @property
    def derived(self) -> bool:
        return self.layer >= 0


@dataclass(frozen=True)
class Effect:
    conditions: tuple[Condition, ...]
    variable: int
    pre: int  # -1: no requirement on the variable
    post: int


@dataclass(frozen=True)
class Operator:
    name: str  # "stack a b": the action's name and arguments, lower case
    prevail: tuple[Condition, ...]
    effects: tuple[Effect, ...]
    cost: int

    @property
    def preconditions(self) -> tuple[Condition, ...]:
        return self.prevail + tuple((e.variable, e.pre) for e in self.effects if e.pre != -1)


@dataclass(frozen=True)
class Axiom:
    conditions: tuple[Condition, ...]
    variable: int
    post: int


@dataclass(frozen=True)
class SASTask:
    variables: tuple[Variable, ...]
    init: tuple[int, ...]
    goal: tuple[Condition, ...]
    operators: tuple[Operator, ...]
    axioms: tuple[Axiom, ...]
    use_costs: bool
    _by_name: dict[str, list[Operator]] = field(default_factory=dict, compare=False, repr=False)

    def operators_named(self, name: str) -> list[Operator]:
        if not self._by_name:
            for op in self.operators:
                self._by_name.setdefault(op.name, []).append(op)
        return self._by_name.get(name, [])

    def fact(self, condition: Condition) -> str:
        """A condition in words: ``clear(b)``, ``not clear(b)``, or the variable's value."""
        variable, value = condition
        text = self.variables[variable].values[value]
        if text.startswith("Atom "):
            return text[5:]
        if text.startswith("NegatedAtom "):
            return "not " + text[12:]
        return f"{self.variables[variable].name}={text}"

    @property
    def trivially_unsolvable(self) -> bool:
        """The translator's stand-in for a task whose goal is not even relaxed-reachable."""
        return (
            len(self.variables) == 1
            and self.variables[0].values == ("Atom dummy(val1)", "Atom dummy(val2)")
            and self.goal == ((0, 1),)
        )


# ------------------------------------------------------------------------- reading


def parse_sas(text: str) -> SASTask:
    """Read a task in the translator's output format (version 3)."""
    lines = iter(text.splitlines())

    def line() -> str:
        try:
            return next(lines).strip()
        except StopIteration:
            raise SASFormatError("unexpected end of file") from None

    def expect(word: str) -> None:
        got = line()
        if got != word:
            raise SASFormatError(f"expected {word!r}, found {got!r}")

    def number() -> int:
        got = line()
        try:
            return int(got)
        except ValueError:
            raise SASFormatError(f"expected a number, found {got!r}") from None

    def pairs(count: int) -> tuple[Condition, ...]:
        result = []
        for _ in range(count):
            var, val = line().split()
            result.append((int(var), int(val)))
        return tuple(result)

    expect("begin_version")
    if (version := number()) != 3:
        raise SASFormatError(f"format version {version}; this reader knows version 3")
    expect("end_version")
    expect("begin_metric")
    use_costs = number() == 1
    expect("end_metric")
    variables = []
    for _ in range(number()):
        expect("begin_variable")
        name, layer, size = line(), number(), number()
        variables.append(Variable(name, layer, tuple(line() for _ in range(size))))
        expect("end_variable")
    for _ in range(number()):  # mutex groups: not needed to simulate
        expect("begin_mutex_group")
        for _ in range(number()):
            line()
        expect("end_mutex_group")
    expect("begin_state")
    init = tuple(number() for _ in variables)
    expect("end_state")
    expect("begin_goal")
    goal = pairs(number())
    expect("end_goal")
    operators = []
    for _ in range(number()):
        expect("begin_operator")
        name = line()
        prevail = pairs(number())
        effects = []
        for _ in range(number()):
            fields = [int(x) for x in line().split()]
            count = fields[0]
            conditions = tuple(
                zip(fields[1 : 1 + 2 * count : 2], fields[2 : 2 + 2 * count : 2], strict=True)
            )
            var, pre, post = fields[1 + 2 * count :]
            effects.append(Effect(conditions, var, pre, post))
        cost = number()
        expect("end_operator")
        operators.append(Operator(name.lower(), prevail, tuple(effects), cost))
    axioms = []
    for _ in range(number()):
        expect("begin_rule")
        conditions = pairs(number())
        var, _pre, post = (int(x) for x in line().split())
        expect("end_rule")
        axioms.append(Axiom(conditions, var, post))
    return SASTask(tuple(variables), init, goal, tuple(operators), tuple(axioms), use_costs)


# ----------------------------------------------------------------------- semantics


def holds(state: Sequence[int], conditions: Iterable[Condition]) -> bool:
    return all(state[var] == val for var, val in conditions)


def evaluate_axioms(task: SASTask, state: list[int]) -> None:
    """Set every derived variable of ``state`` (in place) as the axioms define it."""
    if not task.axioms:
        return
    layers: dict[int, list[Axiom]] = {}
    for axiom in task.axioms:
        layers.setdefault(task.variables[axiom.variable].layer, []).append(axiom)
    for index, variable in enumerate(task.variables):
        if variable.derived:
            state[index] = task.init[index]
    for layer in sorted(layers):
        changed = True
        while changed:
            changed = False
            for axiom in layers[layer]:
                if state[axiom.variable] != axiom.post and holds(state, axiom.conditions):
                    state[axiom.variable] = axiom.post
                    changed = True


def initial_state(task: SASTask) -> list[int]:
    state = list(task.init)
    evaluate_axioms(task, state)
    return state


def successor(task: SASTask, state: Sequence[int], op: Operator) -> list[int]:
    """The state after ``op`` (assumed applicable), axioms evaluated."""
    fired = [e for e in op.effects if holds(state, e.conditions)]
    result = list(state)
    for effect in fired:
        result[effect.variable] = effect.post
    evaluate_axioms(task, result)
    return result


def step_name(action: str) -> str:
    """``(Stack A  B)`` -> ``stack a b`` (the translator's operator names)."""
    return " ".join(action.strip().strip("()").lower().split())


@dataclass(frozen=True)
class PlanCheck:
    """What a plan (or schedule) does in the task: valid, or the first reason it is not."""

    valid: bool
    reason: str = ""
    cost: int | None = None  # the plan's cost when valid
    final_state: tuple[int, ...] | None = field(default=None, compare=False, repr=False)


def apply_step(task: SASTask, state: Sequence[int], action: str) -> list[int] | str:
    """The state after ``action``, or why it cannot be applied (a sentence)."""
    candidates = task.operators_named(step_name(action))
    if not candidates:
        return (
            f"{action} is not a ground action of the task as Fast Downward grounds it "
            "(unknown name or object, or never applicable from the initial state)"
        )
    for op in candidates:
        if holds(state, op.preconditions):
            return successor(task, state, op)
    failing = [c for c in candidates[0].preconditions if state[c[0]] != c[1]]
    return f"{action}: precondition {task.fact(failing[0])} does not hold"


def cost_of(task: SASTask, action: str, state: Sequence[int]) -> int:
    if not task.use_costs:
        return 1
    for op in task.operators_named(step_name(action)):
        if holds(state, op.preconditions):
            return op.cost
    raise ValueError(f"{action} does not apply")


def run_plan(task: SASTask, plan: Sequence[str]) -> PlanCheck:
    """Apply ``plan`` from the initial state; valid when every step applies and the goal holds."""
    return run_parallel(task, [[action] for action in plan])


def run_sequence(task: SASTask, state: Sequence[int], actions: Iterable[str]) -> list[int] | str:
    """The state after ``actions`` one after the other, or why one cannot be applied."""
    current = list(state)
    for action in actions:
        after = apply_step(task, current, action)
        if isinstance(after, str):
            return after
        current = after
    return current


def run_parallel(task: SASTask, steps: Sequence[Sequence[str]]) -> PlanCheck:
    """Check a joint schedule: the actions of every time step must run one after the other
    in every order from the state before the step (every order up to ``MAX_ORDERS_CHECKED``
    actions, else every pair both ways) and every order must reach the same state; the goal
    must hold after the last step. Cost: the sum over all actions.

    This is the semantic reading of "may act in the same time step": the agents' actions
    commute. Graphplan's non-interference (no action deletes another's precondition or adds
    what another deletes) implies it, so a schedule that rule accepts is never rejected for
    its concurrency, while an order-dependent step always is.
    """
    if task.trivially_unsolvable:
        return PlanCheck(False, "the translator proved the goal unreachable (no relaxed plan)")
    state = initial_state(task)
    cost = 0
    for number, actions in enumerate(steps, start=1):
        reached = run_sequence(task, state, actions)
        if isinstance(reached, str):
            return PlanCheck(False, f"step {number}: {reached}")
        if len(actions) < 2:
            groups = []
        elif len(actions) <= MAX_ORDERS_CHECKED:
            groups = [list(itertools.permutations(actions))]
        else:
            groups = [[(a, b), (b, a)] for a, b in itertools.combinations(actions, 2)]
        for orders in groups:
            outcomes = [run_sequence(task, state, order) for order in orders]
            if len(orders[0]) == len(actions):
                outcomes.append(reached)
            for order, outcome in zip(orders, outcomes, strict=False):
                if isinstance(outcome, str):
                    return PlanCheck(
                        False, f"step {number} in the order {', '.join(order)}: {outcome}"
                    )
            if any(outcome != outcomes[0] for outcome in outcomes):
                return PlanCheck(
                    False,
                    f"step {number}: {', '.join(orders[0])} reach different states in "
                    "different orders (they interfere)",
                )
        for action in actions:
            cost += cost_of(task, action, state)
        state = reached
    missing = [c for c in task.goal if state[c[0]] != c[1]]
    if missing:
        return PlanCheck(False, f"the goal {task.fact(missing[0])} does not hold at the end")
    return PlanCheck(True, cost=cost, final_state=tuple(state))


# ----------------------------------------------------- per-agent copies of agent facts


def atom_predicate(value: str) -> str | None:
    """``Atom holding(a)`` / ``NegatedAtom holding(a)`` -> ``holding``; None for other values."""
    for prefix in ("Atom ", "NegatedAtom "):
        if value.startswith(prefix):
            return value[len(prefix) :].split("(", 1)[0].strip().lower()
    return None


def agent_operator_name(agent: int, action: str) -> str:
    """The name of ``action`` done by agent ``agent`` in :func:`multi_agent_task`."""
    return f"agent{agent}: {step_name(action)}"


def multi_agent_task(task: SASTask, agent_predicates: Iterable[str], agents: int) -> SASTask:
    """The N-agent task in which each agent has its own copy of the agent-specific facts.

    A variable is agent-specific when it stands for an atom of an agent predicate (translate
    with invariant synthesis off, so that every atom is a variable of its own). Every agent
    starts with the initial state's copy; agent-specific goal conditions must hold for every
    agent; environment variables are shared. Agent ``i``'s operators are the task's operators
    on its own copy, named by :func:`agent_operator_name`. A derived variable whose axioms
    read an agent-specific variable (directly or through other derived ones) is agent-specific
    too: each agent derives its own copy from its view (the shared variables and its own
    copies), with its own copy of those axioms. Raises ``ValueError`` when an agent-specific
    state variable is not binary.
    """
    wanted = {p.lower() for p in agent_predicates}
    own = [
        i
        for i, v in enumerate(task.variables)
        if not v.derived and any(atom_predicate(x) in wanted for x in v.values)
    ]
    for i in own:
        names = {atom_predicate(x) for x in task.variables[i].values}
        if len(task.variables[i].values) != 2 or len(names) != 1:
            raise ValueError(
                f"variable {task.variables[i].name} mixes facts ({task.variables[i].values}); "
                "translate with --invariant-generation-max-candidates 0"
            )
    own_set = set(own)
    changed = True
    while changed:  # derived variables that read agent-specific ones, transitively
        changed = False
        for axiom in task.axioms:
            if axiom.variable not in own_set and any(v in own_set for v, _ in axiom.conditions):
                own_set.add(axiom.variable)
                own.append(axiom.variable)
                changed = True
    copy: list[dict[int, int]] = [{i: i for i in own}]
    variables = list(task.variables)
    init = list(task.init)
    for _ in range(1, agents):
        mapping = {}
        for i in own:
            mapping[i] = len(variables)
            variables.append(task.variables[i])
            init.append(task.init[i])
        copy.append(mapping)

    def moved(conditions: Iterable[Condition], agent: int) -> tuple[Condition, ...]:
        return tuple((copy[agent].get(var, var), val) for var, val in conditions)

    operators = []
    for agent in range(agents):
        for op in task.operators:
            effects = tuple(
                Effect(
                    moved(e.conditions, agent),
                    copy[agent].get(e.variable, e.variable),
                    e.pre,
                    e.post,
                )
                for e in op.effects
            )
            name = agent_operator_name(agent, op.name)
            operators.append(Operator(name, moved(op.prevail, agent), effects, op.cost))
    axioms = [a for a in task.axioms if a.variable not in own_set]
    for agent in range(agents):
        axioms += [
            Axiom(moved(a.conditions, agent), copy[agent][a.variable], a.post)
            for a in task.axioms
            if a.variable in own_set
        ]
    goal = [c for c in task.goal if c[0] not in own_set]
    for agent in range(agents):
        goal += [c for c in moved(task.goal, agent) if c not in goal]
    return SASTask(
        tuple(variables), tuple(init), tuple(goal), tuple(operators), tuple(axioms), task.use_costs
    )
