"""twostep.pddl.grounded (with twostep.pddl.sas, translator): the state model beyond STRIPS.

Each PDDL construct the model handles natively, on small domains of our own with
hand-derived expectations: conditional effects whose condition depends on the state,
derived predicates with negation across layers, action costs from static functions,
disjunctive preconditions, universal effects, a predicate declared with one parameter name
twice. Progression and the parallel scorer on conditional effects are checked against a
brute-force simulator written here, apart from the model's own code (it reads only the
grounded actions' data: preconditions, effects and their conditions).
"""

from __future__ import annotations

import functools
import itertools
from collections import deque
from collections.abc import Sequence
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.examples import GRAPH, GRAPH_PROBLEM, ROAD_LENGTHS, ROAD_LENGTHS_PROBLEM
from twostep.makespan import ScheduleError, check_schedule, parallel_length
from twostep.pddl import Fact, Goal, PDDLError, Problem, parse_goal, parse_problem
from twostep.planner import PlannerSettings, plan
from twostep.plans.progression import progress_state
from twostep.plans.simulate import GroundAction, Grounder, simulate

OPTIMAL = PlannerSettings(alias="astar-blind", search_time_limit_s=30)

LAMPS = """
(define (domain lamps)
 (:requirements :strips :conditional-effects :negative-preconditions)
 (:predicates (on ?l) (wired ?a ?b))
 (:action toggle :parameters (?l)
   :effect (and (when (on ?l) (not (on ?l))) (when (not (on ?l)) (on ?l))))
 (:action flip-all :parameters ()
   :effect (forall (?l) (and (when (on ?l) (not (on ?l))) (when (not (on ?l)) (on ?l)))))
 (:action press :parameters (?a ?b) :precondition (wired ?a ?b)
   :effect (when (on ?a) (on ?b))))
"""
LAMPS_PROBLEM = """
(define (problem lamps-1) (:domain lamps) (:objects l1 l2 l3)
 (:init (on l1) (wired l1 l2))
 (:goal (and (not (on l1)) (on l2) (on l3))))
"""


# A disjunctive precondition, and a predicate declared with one parameter name twice
# (IPC zenotravel's style), with "(in?x ?x)" written without a space as well.
DOORS = """
(define (domain doors)
 (:requirements :strips :disjunctive-preconditions)
 (:predicates (has-key ?r) (open ?r) (unlocked ?r) (inside ?r) (in ?obj ?obj))
 (:action open-door :parameters (?r) :precondition (unlocked ?r) :effect (open ?r))
 (:action enter :parameters (?r)
   :precondition (or (has-key ?r) (open ?r))
   :effect (inside ?r))
 (:action stash :parameters (?x ?r) :precondition (inside ?r) :effect (in?x ?r)))
"""
DOORS_PROBLEM = """
(define (problem doors-1) (:domain doors) (:objects r1 r2 r3 box)
 (:init (has-key r1) (unlocked r2))
 (:goal (and (inside r1) (inside r2) (in box r2))))
"""


def problem(domain: str, task: str) -> Problem:
    return parse_problem(domain, task)


def ground(prob: Problem, *actions: str) -> list[GroundAction]:
    return Grounder(prob).ground_plan(actions)


def test_conditional_effects_depend_on_the_state_before_the_action() -> None:
    prob = problem(LAMPS, LAMPS_PROBLEM)
    toggle, press, flip = ground(prob, "(toggle l1)", "(press l1 l2)", "(flip-all)")
    # the translator keeps each `when` as it is: no variants, conditions intact
    assert not toggle.alternatives and len(toggle.effects) == 2
    assert toggle.possible_add == toggle.possible_delete == {("on", "l1")}
    assert toggle.condition_facts == {("on", "l1")}
    init = prob.init
    assert init == {("on", "l1"), ("wired", "l1", "l2")}
    off = toggle.apply(init)
    assert ("on", "l1") not in off
    assert toggle.apply(off) == init  # toggled twice: back on
    assert press.apply(init) == init | {("on", "l2")}  # l1 is on: l2 goes on
    assert press.apply(off) == off  # l1 is off: nothing happens
    # a universal conditional effect: every lamp flips, each by its own state
    assert flip.apply(init) == {("wired", "l1", "l2"), ("on", "l2"), ("on", "l3")}
    # flip-all reaches the goal in one step; blind A* on the original file agrees
    result = plan(prob, OPTIMAL)
    assert result.plan == ("(flip-all)",) and result.cost == 1


def test_derived_predicates_with_negation_across_layers() -> None:
    prob = problem(GRAPH, GRAPH_PROBLEM)
    rules = prob.grounded.axioms.rules
    layers = {r.head[0]: r.layer for r in rules}
    assert layers["reach"] < layers["cut-off"]  # not reach: settled in a lower layer
    # n1 is the source; n2, n3 reachable through open edges; n4 behind a closed one
    reach = {("reach", n) for n in ("n1", "n2", "n3")}
    assert reach | {("cut-off", "n4")} <= prob.init
    assert not {("reach", "n4"), ("cut-off", "n2")} & prob.init
    (close,) = ground(prob, "(close n1 n2)")
    after = close.apply(prob.init)
    assert ("reach", "n1") in after and ("reach", "n2") not in after
    assert {("cut-off", n) for n in ("n2", "n3", "n4")} <= after
    visit_n2, lost_n2 = ground(prob, "(visit n2)", "(mark-lost n2)")
    assert visit_n2.applicable(prob.init) and not visit_n2.applicable(after)
    assert lost_n2.applicable(after) and not lost_n2.applicable(prob.init)
    # open n3-n4, visit n4, close n2-n3 (n3 and n4 cut off), mark n3 lost: 4 steps,
    # and visiting n4 must come before the close
    result = plan(prob, OPTIMAL)
    assert result.plan is not None and len(result.plan) == 4
    final = simulate(prob.init, ground(prob, *result.plan))
    assert prob.goal.holds(final)
    with pytest.raises(Exception, match="reach n4"):
        simulate(prob.init, ground(prob, "(open-gate n3 n4)", "(close n2 n3)", "(visit n4)"))


def test_costs_from_static_functions() -> None:
    prob = problem(ROAD_LENGTHS, ROAD_LENGTHS_PROBLEM)
    costs = {str(a): a.cost for a in prob.grounded.actions.values()}
    assert costs == {
        "(drive a b)": 5,
        "(drive b d)": 5,
        "(drive a c)": 2,
        "(drive c d)": 9,
        "(drive a d)": 20,
    }
    # cheapest: a-b-d (10) beats a-c-d (11) and the direct road (20)
    result = plan(prob, OPTIMAL)
    assert result.plan == ("(drive a b)", "(drive b d)") and result.cost == 10
    # the problem the planner receives keeps the numeric facts when its state changes
    moved = prob.with_state(prob.init - {("at", "a")} | {("at", "b")})
    result = plan(moved, OPTIMAL)
    assert result.plan == ("(drive b d)",) and result.cost == 5


def test_disjunctive_preconditions_and_duplicate_parameter_names() -> None:
    prob = problem(DOORS, DOORS_PROBLEM)
    assert prob.domain.predicates["in"] == ("object", "object")
    enter_1, enter_2, open_2 = ground(prob, "(enter r1)", "(enter r2)", "(open-door r2)")
    assert enter_1.applicable(prob.init)  # by its key
    assert not enter_2.applicable(prob.init)  # neither a key nor an open door, yet
    assert enter_2.failing_precondition(prob.init) is not None
    assert enter_2.applicable(open_2.apply(prob.init))  # by the open door
    with pytest.raises(Exception, match="never applicable"):
        ground(prob, "(enter r3)")  # r3 can never be opened: not an action of the task
    # enter r1; open r2, enter r2, stash the box there
    result = plan(prob, OPTIMAL)
    assert result.plan is not None and len(result.plan) == 4
    assert prob.goal.holds(simulate(prob.init, ground(prob, *result.plan)))


def test_a_derived_precondition_interferes_with_what_it_is_derived_from() -> None:
    prob = problem(GRAPH, GRAPH_PROBLEM)
    close, visit = ground(prob, "(close n2 n3)", "(visit n3)")
    # closing n2-n3 cuts n3 off: visiting n3 must come first, not in the same step
    assert ("open", "n2", "n3") in visit.condition_facts
    goal = Goal(frozenset({("visited", "n3")}))
    for mode in ("exact", "paper"):
        result = parallel_length([[close], [visit]], prob.init, goal, (), mode)
        assert result.length == 2
        assert result.steps == (((1, "(visit n3)"),), ((0, "(close n2 n3)"),))
    with pytest.raises(ScheduleError, match="interfere"):
        check_schedule(
            (((0, "(close n2 n3)"), (1, "(visit n3)")),), [[close], [visit]], prob.init, goal, ()
        )


@pytest.mark.parametrize(
    ("goal", "order"),
    [
        # toggle l2 (off -> on), then press l1 l2 (l1 on: l2 on): l2 ends on
        ("(on l2)", ["(toggle l2)", "(press l1 l2)"]),
        # press first (l2 on), toggle after (on -> off): l2 ends off
        ("(not (on l2))", ["(press l1 l2)", "(toggle l2)"]),
    ],
)
def test_the_scorer_orders_conditional_effects_as_the_goal_needs(
    goal: str, order: list[str]
) -> None:
    prob = problem(LAMPS, LAMPS_PROBLEM)
    plans = [ground(prob, "(toggle l2)"), ground(prob, "(press l1 l2)")]
    target = parse_goal(goal, prob)
    for mode in ("exact", "paper"):
        result = parallel_length(plans, prob.init, target, (), mode)
        assert result.length == 2  # they interfere (both may change l2): one at a time
        assert [action for step in result.steps for _, action in step] == order
    # lamps that never meet share a step
    apart = [ground(prob, "(toggle l2)"), ground(prob, "(toggle l3)")]
    assert parallel_length(apart, prob.init, Goal(), (), "exact").length == 1


# ----------------------------------------------------------------- brute force

# A switchboard for random tests: conditional effects on shared lamps and on each agent's
# own facts (ready, tired), the latter conditioned on the shared state.
BOARD = """
(define (domain board)
 (:requirements :strips :conditional-effects :negative-preconditions)
 (:predicates (on ?l) (wired ?a ?b) (ready) (tired))
 (:action toggle :parameters (?l) :precondition (ready)
   :effect (and (when (on ?l) (not (on ?l))) (when (not (on ?l)) (on ?l))))
 (:action press :parameters (?a ?b) :precondition (wired ?a ?b)
   :effect (and (when (on ?a) (on ?b)) (when (on ?b) (tired))))
 (:action rest :parameters () :precondition (tired) :effect (and (not (tired)) (ready)))
 (:action work :parameters (?l) :precondition (on ?l) :effect (not (ready))))
"""
BOARD_PROBLEM = """
(define (problem board-1) (:domain board) (:objects l1 l2 l3)
 (:init (ready) (on l1) (wired l1 l2) (wired l2 l3) (wired l3 l1))
 (:goal (and)))
"""
BOARD_AGENT = ("ready", "tired")


def effects_in(action: GroundAction, state: frozenset[Fact]) -> tuple[set[Fact], set[Fact]]:
    """(adds, deletes) by the PDDL rule, from the action's data alone."""
    chosen = next(
        v
        for v in (action, *action.alternatives)
        if v.pre_positive <= state and not v.pre_negative & state
    )
    add, delete = set(chosen.add), set(chosen.delete)
    for effect in chosen.effects:
        if effect.condition_positive <= state and not effect.condition_negative & state:
            add |= effect.add
            delete |= effect.delete
    return add, delete


def brute_apply(action: GroundAction, state: frozenset[Fact]) -> frozenset[Fact]:
    add, delete = effects_in(action, state)
    return frozenset((state - delete) | add)


def possible(action: GroundAction) -> tuple[set[Fact], set[Fact], set[Fact]]:
    """(possible adds, possible deletes, condition facts), written out plainly."""
    add, delete, conditions = set(action.add), set(action.delete), set()
    for effect in action.effects:
        add |= effect.add
        delete |= effect.delete
        conditions |= effect.condition_positive | effect.condition_negative
    return add, delete, conditions


def clash(a: GroundAction, b: GroundAction, private: Sequence[str]) -> bool:
    def shared(facts: set[Fact]) -> set[Fact]:
        return {f for f in facts if f[0] not in private}

    for x, y in ((a, b), (b, a)):
        x_add, x_delete, _ = possible(x)
        y_add, y_delete, y_conditions = possible(y)
        if shared(x_delete) & (set(y.pre_positive) | y_add):
            return True
        if shared(x_add) & (set(y.pre_negative) | y_delete):
            return True
        if shared(x_add | x_delete) & y_conditions:
            return True
    return False


def brute_force_length(
    plans: Sequence[Sequence[GroundAction]],
    init: frozenset[Fact],
    goal: Goal,
    private: Sequence[str],
) -> int | None:
    """Breadth-first over (indices, environment, agent copies), any set of agents per step."""
    environment = frozenset(f for f in init if f[0] not in private)
    own = frozenset(f for f in init if f[0] in private)
    start = (tuple(0 for _ in plans), environment, tuple(own for _ in plans))
    seen = {start}
    queue = deque([(start, 0)])
    while queue:
        (indices, env, copies), depth = queue.popleft()
        if all(i == len(p) for i, p in zip(indices, plans, strict=True)):
            shared_goal = all(f in env for f in goal.positive if f[0] not in private)
            shared_goal &= not any(f in env for f in goal.negative if f[0] not in private)
            own_goal = all(
                all(f in c for f in goal.positive if f[0] in private)
                and not any(f in c for f in goal.negative if f[0] in private)
                for c in copies
            )
            if shared_goal and own_goal:
                return depth
            continue
        active = [a for a, i in enumerate(indices) if i < len(plans[a])]
        for size in range(1, len(active) + 1):
            for chosen in itertools.combinations(active, size):
                actions = {a: plans[a][indices[a]] for a in chosen}
                views = {a: env | copies[a] for a in chosen}
                if not all(
                    any(
                        v.pre_positive <= views[a] and not v.pre_negative & views[a]
                        for v in (actions[a], *actions[a].alternatives)
                    )
                    for a in chosen
                ):
                    continue
                if any(
                    clash(actions[a], actions[b], private)
                    for a, b in itertools.combinations(chosen, 2)
                ):
                    continue
                new_env, new_copies = set(env), list(copies)
                adds, deletes = set(), set()
                for a in chosen:
                    add, delete = effects_in(actions[a], views[a])
                    adds |= {f for f in add if f[0] not in private}
                    deletes |= {f for f in delete if f[0] not in private}
                    mine = {f for f in add if f[0] in private}
                    gone = {f for f in delete if f[0] in private}
                    new_copies[a] = frozenset((copies[a] - gone) | mine)
                new_env = (new_env - deletes) | adds
                node = (
                    tuple(i + (a in chosen) for a, i in enumerate(indices)),
                    frozenset(new_env),
                    tuple(new_copies),
                )
                if node not in seen:
                    seen.add(node)
                    queue.append((node, depth + 1))
    return None


def test_progression_with_conditional_effects_matches_the_brute_force() -> None:
    prob = problem(BOARD, BOARD_PROBLEM)
    steps = ["(press l1 l2)", "(toggle l3)", "(press l2 l3)", "(rest)", "(toggle l3)",
             "(press l3 l1)", "(work l1)"]  # fmt: skip
    actions = ground(prob, *steps)
    state = prob.init
    for action in actions:
        state = brute_apply(action, state)
    assert simulate(prob.init, actions) == state
    # hand-derived: press l1 l2 turns l2 on (l1 is on); toggle l3 turns l3 on; press l2 l3
    # keeps l3 on and tires the agent (l3 is on); rest: ready, not tired; toggle l3 turns
    # it off; press l3 l1 does not light l1 (l3 is off) but tires the agent (l1 is on);
    # work l1: not ready
    assert state == {("on", "l1"), ("on", "l2"), ("tired",), ("wired", "l1", "l2"),
                     ("wired", "l2", "l3"), ("wired", "l3", "l1")}  # fmt: skip
    environment = progress_state(prob.init, actions, BOARD_AGENT)
    assert environment == {f for f in state if f[0] not in BOARD_AGENT}


@functools.cache
def board() -> Problem:
    return problem(BOARD, BOARD_PROBLEM)


def _board_actions(prob: Problem) -> list[GroundAction]:
    return sorted(prob.grounded.actions.values(), key=str)


@st.composite
def board_cases(draw: st.DrawFn) -> tuple[list[list[int]], list[int], list[int]]:
    agents = draw(st.integers(1, 3))
    plans = [draw(st.lists(st.integers(0, 9), max_size=3)) for _ in range(agents)]
    positive = draw(st.lists(st.integers(0, 2), max_size=2))
    negative = draw(st.lists(st.integers(0, 2), max_size=1))
    return plans, positive, negative


@settings(max_examples=60, deadline=None)
@given(board_cases())
def test_the_scorer_agrees_with_brute_force_on_conditional_effects(
    case: tuple[list[list[int]], list[int], list[int]],
) -> None:
    prob = board()
    pool = _board_actions(prob)
    picks, positive, negative = case
    plans = [[pool[k % len(pool)] for k in plan] for plan in picks]
    lamps = ("l1", "l2", "l3")
    goal = Goal(
        frozenset(("on", lamps[k]) for k in positive),
        frozenset(("on", lamps[k]) for k in negative) - {("on", lamps[k]) for k in positive},
    )
    expected = brute_force_length(plans, prob.init, goal, BOARD_AGENT)
    if expected is None:
        with pytest.raises(ScheduleError):
            parallel_length(plans, prob.init, goal, BOARD_AGENT, "exact")
        return
    result = parallel_length(plans, prob.init, goal, BOARD_AGENT, "exact")
    assert result.length == expected
    check_schedule(result.steps, plans, prob.init, goal, BOARD_AGENT)


@pytest.mark.parametrize(
    ("requirements", "body", "line", "fragment"),
    [
        (  # temporal planning: a section Fast Downward does not plan with
            ":durative-actions",
            "(:durative-action a :parameters () :duration (= ?duration 1)\n"
            "   :condition (at start (p)) :effect (at end (p)))",
            4,
            "durative actions",
        ),
        (":strips :numeric-fluents", "(:action a :effect (p))", 2, ":numeric-fluents"),
        (
            ":strips",
            "(:action a :parameters ()\n   :precondition (> (fuel) 0) :effect (p))",
            5,
            "numeric conditions (> ...)",
        ),
        (
            ":strips",
            "(:action a :parameters ()\n   :effect (and (p) (decrease (fuel) 1)))",
            5,
            "numeric effects other than (increase (total-cost) ...)",
        ),
        (":strips :typing", "(:types block\n   number)", 5, 'the type "number" is reserved'),
    ],
)
def test_what_fast_downward_cannot_plan_is_named_with_file_and_line(
    requirements: str, body: str, line: int, fragment: str
) -> None:
    domain = (
        f"(define (domain d)\n (:requirements {requirements})\n (:predicates (p))"
        f" (:functions (fuel))\n {body})"
    )
    task = "(define (problem x) (:domain d) (:init) (:goal (p)))"
    with pytest.raises(PDDLError) as info:
        parse_problem(domain, task, "dom.pddl", "prob.pddl")
    assert (info.value.source, info.value.line) == ("dom.pddl", line)
    assert fragment in str(info.value)


@pytest.mark.parametrize(
    ("metric", "accepted"),
    [
        ("(:metric minimize (total-cost))", True),
        ("(:metric  MINIMIZE\n   (total-cost ))", True),
        ("(:metric minimize (total-time))", False),  # a temporal metric (IPC parking)
        ("(:metric maximize (total-cost))", False),
        ("(:metric minimize (fuel))", False),
    ],
)
def test_only_the_total_cost_metric_is_accepted(metric: str, accepted: bool) -> None:
    domain = "(define (domain d) (:requirements :strips) (:predicates (p)) (:action a :effect (p)))"
    task = f"(define (problem x) (:domain d) (:init)\n (:goal (p))\n {metric})"
    if accepted:
        assert parse_problem(domain, task, "dom.pddl", "prob.pddl").grounded.actions
        return
    with pytest.raises(PDDLError) as info:
        parse_problem(domain, task, "dom.pddl", "prob.pddl")
    assert (info.value.source, info.value.line) == ("prob.pddl", 3)
    assert "(:metric minimize (total-cost))" in str(info.value)


def test_the_cached_problem_holds_the_grounding(tmp_path: Path) -> None:
    from twostep.pddl import load_problem

    (tmp_path / "domain.pddl").write_text(GRAPH)
    (tmp_path / "p01.pddl").write_text(GRAPH_PROBLEM)
    first = load_problem(tmp_path / "domain.pddl", tmp_path / "p01.pddl", tmp_path / "cache")
    again = load_problem(tmp_path / "domain.pddl", tmp_path / "p01.pddl", tmp_path / "cache")
    assert again.is_grounded and again.init == first.init
    (close,) = ground(again, "(close n1 n2)")
    assert ("cut-off", "n2") in close.apply(again.init)  # the axioms came back too
