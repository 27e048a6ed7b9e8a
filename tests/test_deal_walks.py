"""plan-deal's walking search on a task whose acting actions need facts only other acting
actions make (a lamp must be trimmed before it is lit; walking trims nothing).

Real domains of this shape (a tent put up before a couple walks on, a car parked behind
another) made plan-deal search the whole walking space again and again for walks that
cannot exist, for minutes. A walk is now not searched for when the target needs a fact no
move adds, and each walk is searched once per SA plan. The deals are checked by
``check_run`` and by the independent validator on the files.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest

from checkers import IndependentValidator
from tests.conftest import own_task
from tests.support.plans import FAST, sa_result
from twostep.dealing import Dealer, DealError, walks
from twostep.dealing.encoding import FactSpace, Step
from twostep.methods import MethodRequest, check_run
from twostep.methods.plan_deal import run_plan_deal
from twostep.plans.simulate import Grounder
from twostep.tasks.benchmark import BenchmarkTask

DOMAIN = """(define (domain lamplighters)
 (:requirements :strips :typing)
 (:types lighter spot lamp)
 (:predicates (stands ?p - lighter ?s - spot) (road ?a ?b - spot)
              (lamp-at ?l - lamp ?s - spot) (dark ?l - lamp) (trimmed ?l - lamp)
              (lit ?l - lamp))
 (:action go :parameters (?p - lighter ?a ?b - spot)
  :precondition (and (stands ?p ?a) (road ?a ?b))
  :effect (and (stands ?p ?b) (not (stands ?p ?a))))
 (:action trim :parameters (?p - lighter ?l - lamp ?s - spot)
  :precondition (and (stands ?p ?s) (lamp-at ?l ?s) (dark ?l))
  :effect (trimmed ?l))
 (:action light :parameters (?p - lighter ?l - lamp ?s - spot)
  :precondition (and (stands ?p ?s) (lamp-at ?l ?s) (dark ?l) (trimmed ?l))
  :effect (and (lit ?l) (not (dark ?l)))))
"""

# a street of five spots, s0 to s4, the lighter at s0, a dark lamp at each of s1..s4
ROADS = " ".join(f"(road s{k} s{k + 1}) (road s{k + 1} s{k})" for k in range(4))
LAMPS = " ".join(f"(lamp-at l{k} s{k}) (dark l{k})" for k in range(1, 5))
PROBLEM = f"""(define (problem evening) (:domain lamplighters)
 (:objects ann - lighter s0 s1 s2 s3 s4 - spot l1 l2 l3 l4 - lamp)
 (:init (stands ann s0) {ROADS} {LAMPS})
 (:goal (and (lit l1) (lit l2) (lit l3) (lit l4))))
"""
PLAN = tuple(
    step
    for k in range(1, 5)
    for step in (f"(go ann s{k - 1} s{k})", f"(trim ann l{k} s{k})", f"(light ann l{k} s{k})")
)
AGENT = ["stands"]


def lamplighters(root: Path, problem: str) -> BenchmarkTask:
    """``problem`` in a lamplighters folder of ``root``, read as task 1."""
    return own_task(root, "lamplighters", DOMAIN, problem)


@pytest.fixture
def task(tmp_path: Path) -> BenchmarkTask:
    return lamplighters(tmp_path, PROBLEM)


@pytest.fixture
def searched(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The targets the walking search is run for from now on, in order."""
    targets: list[str] = []
    search = walks.Walker._search

    def counted(self: walks.Walker, *args: object, **kwargs: object) -> list[walks.Step]:
        targets.append(str(args[-1]))
        return search(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(walks.Walker, "_search", counted)
    return targets


def test_no_walk_is_searched_for_a_fact_no_move_adds(
    task: BenchmarkTask, searched: list[str]
) -> None:
    dealer = Dealer(task.problem, PLAN, AGENT)
    walker, space = dealer.walker, dealer.space
    env, own = dealer.init
    ground = Grounder(task.problem).ground
    light = space.step(ground("(light ann l3 s3)"))  # l3 is not trimmed: no walk helps
    trim = space.step(ground("(trim ann l3 s3)"))  # three steps of go away
    # the search itself, over every move, finds no walk to the light either
    with pytest.raises(DealError):
        walker._search(env, own, light.applicable, None, str(light))
    searched.clear()  # the searches from here on
    with pytest.raises(DealError, match="no walk"):
        walker.walk_to(env, own, light)
    assert searched == []
    path = walker.walk_to(env, own, trim)
    assert [str(s) for s in path] == ["(go ann s0 s1)", "(go ann s1 s2)", "(go ann s2 s3)"]
    for step in path:
        env, own = step.apply(env, own)
    assert trim.applicable(env, own) and not light.applicable(env, own)
    # asked again (the deals of one plan do): the same walk, not searched again
    assert walker.walk_to(*dealer.init, trim) == path
    assert searched == [str(trim)]


@pytest.mark.parametrize("agents", [2, 3])
def test_lamps_dealt_and_validated(task: BenchmarkTask, agents: int) -> None:
    run = run_plan_deal(MethodRequest(task, agents, FAST, AGENT, sa_plan=sa_result(PLAN)))
    assert run.success and run.exec_length is not None
    check_run(task.problem, run, AGENT)
    verdict = IndependentValidator(task.domain_path, task.problem_path).check_schedule(
        run.agent_order, run.plans, run.schedule, AGENT
    )
    assert verdict.valid, verdict.reason
    # the second lighter walks to the far lamps while the first lights the near ones
    assert run.fallback is None and run.exec_length < len(PLAN)
    assert sorted(a for plan in run.plans.values() for a in plan if "go" not in a) == sorted(
        a for a in PLAN if "go" not in a
    )


# A one-way street: roads lead from s0 to s4 only. Walking adds `stands` at every spot, so
# once the lighter has walked past a lamp, nothing rules the lamp out but where walks go.
ONE_WAY = PROBLEM.replace(ROADS, " ".join(f"(road s{k} s{k + 1})" for k in range(4)))


@dataclass
class AtS3:
    """The lighter on the one-way street, walked to s3: the walker, the fact space, the
    state, and trimming a lamp it walked past (s1) and one ahead (s4)."""

    walker: walks.Walker
    space: FactSpace
    env: int
    own: int
    behind: Step
    ahead: Step


def at_s3(tmp_path: Path) -> AtS3:
    task = lamplighters(tmp_path, ONE_WAY)
    dealer = Dealer(task.problem, PLAN, AGENT)
    space = dealer.space
    ground = Grounder(task.problem).ground
    env, own = dealer.init
    for move in ("(go ann s0 s1)", "(go ann s1 s2)", "(go ann s2 s3)"):
        env, own = space.step(ground(move)).apply(env, own)
    behind = space.step(ground("(trim ann l1 s1)"))  # at s1, walked past
    ahead = space.step(ground("(trim ann l4 s4)"))
    return AtS3(dealer.walker, space, env, own, behind, ahead)


def test_no_walk_is_searched_for_a_place_no_road_leads_back_to(
    tmp_path: Path, searched: list[str]
) -> None:
    street = at_s3(tmp_path)
    walker, space, env, own = street.walker, street.space, street.env, street.own
    behind, ahead = street.behind, street.ahead
    # a move adds (stands ann s1) (going from s0), so that alone rules nothing out
    assert not walker.out_of_reach(env, own, (behind.pre_env, behind.pre_own), (0, 0))
    # the search itself, over every move, finds no walk back
    with pytest.raises(DealError):
        walker._search(env, own, behind.applicable, None, str(behind))
    # from s3, even without deletes, walks reach s3 and s4 only
    _, reach_own = walker.relaxed(env, own)
    stands = {f for f in space.own_facts(reach_own) if f[0] == "stands"}
    assert stands == {("stands", "ann", "s3"), ("stands", "ann", "s4")}
    searched.clear()  # the searches from here on
    with pytest.raises(DealError, match="no walk"):
        walker.walk_to(env, own, behind)
    assert searched == []
    assert [str(s) for s in walker.walk_to(env, own, ahead)] == ["(go ann s3 s4)"]
    assert searched == [str(ahead)]


def test_the_relaxed_check_stops_once_the_target_is_reached(tmp_path: Path) -> None:
    # From s3 on the one-way street (the test above): s4's lamp is one move away, so the
    # relaxed fixpoint stops early and keeps nothing; s1's lamp is never reached, so the
    # fixpoint runs to its end, is kept, and is the one relaxed() gives (s3 and s4).
    street = at_s3(tmp_path)
    walker, space, env, own = street.walker, street.space, street.env, street.own
    behind, ahead = street.behind, street.ahead
    assert walker.reaches(env, own, ahead.pre_env, ahead.pre_own)
    assert (env, own) not in walker._relaxed
    assert not walker.reaches(env, own, behind.pre_env, behind.pre_own)
    kept = walker._relaxed[(env, own)]
    assert kept == walker.relaxed(env, own)
    stands = {f for f in space.own_facts(kept[1]) if f[0] == "stands"}
    assert stands == {("stands", "ann", "s3"), ("stands", "ann", "s4")}
