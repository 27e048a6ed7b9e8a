"""twostep.dealing.improve: plan-deal's owner search, a first-improvement hill climb over
the pieces' agents.

The search itself is checked on a model whose runs are derived by hand (pieces of fixed
length, each agent doing its pieces one after the other); plan-deal with it on a
blocksworld task whose shortest joint schedule is derived by hand, every schedule checked
by ``check_run`` and by unified-planning's validator.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import pytest

from tests.examples import BW
from tests.support.plans import FAST, blocks_task, check_valid_run, sa_result
from twostep.dealing import Dealer, DealError
from twostep.dealing.improve import search_owners
from twostep.dealing.timeline import JointSteps
from twostep.methods import MethodRequest, run_single_agent
from twostep.methods.plan_deal import run_plan_deal
from twostep.tasks.benchmark import load_task

LENGTHS = (3, 3, 2, 2)  # the model's pieces: how many steps each takes


class Model:
    """The model's raw runs: each agent does its pieces in order, one step per time step
    (a time step lists one dummy entry per agent acting in it); ``work`` counts the time
    steps run so far."""

    def __init__(self) -> None:
        self.work = 0

    def run(self, owner: Sequence[int]) -> JointSteps:
        loads = [sum(n for n, a in zip(LENGTHS, owner, strict=True) if a == b) for b in (0, 1)]
        self.work += max(loads)
        return [[(a, None) for a in (0, 1) if loads[a] > t] for t in range(max(loads))]  # type: ignore[misc]

    def search(self, start: Sequence[int], **bounds: int) -> tuple[list[int], int, int]:
        found = search_owners(
            [0, 0, 0, 0], start, 2, self.run, lambda steps: steps, lambda: self.work, **bounds
        )
        return found.owner, found.length, found.moves


def test_first_improvement_in_start_order() -> None:
    # All four pieces on agent 0: 10 steps. Piece 0 to agent 1: loads 7 / 3, kept (7).
    # Piece 1 to agent 1: 4 / 6, kept (6). Piece 2 or 3 to agent 1: 2 / 8, not shorter;
    # to agent 0 each already is. Two moves, 6 steps: a local optimum, as the climb is
    # first-improvement (3+2 / 3+2 would take 5).
    assert Model().search([0, 1, 2, 3]) == ([1, 1, 0, 0], 6, 2)


def test_the_start_order_decides_which_piece_moves_first() -> None:
    # Pieces started in the order 2, 3, 0, 1: piece 2 to agent 1 (8 / 2: 8), kept; piece 3
    # (6 / 4: 6), kept; piece 0 to agent 1: 3 / 7, not shorter; piece 1 the same. 6 steps.
    assert Model().search([2, 3, 0, 1]) == ([0, 0, 1, 1], 6, 2)


def test_the_search_stops_when_the_work_is_spent_or_the_floor_reached() -> None:
    # The first run costs 10 steps of work: with a bound of 10, no trial is made. With 17,
    # one: piece 0 to agent 1 (7 steps), after which 17 are spent. With a floor of 7 the
    # search stops after that move too, however much work is left (the model's clean-up
    # drops nothing).
    assert Model().search([0, 1, 2, 3], work=10) == ([0, 0, 0, 0], 10, 0)
    assert Model().search([0, 1, 2, 3], work=17) == ([1, 0, 0, 0], 7, 1)
    assert Model().search([0, 1, 2, 3], floor=7) == ([1, 0, 0, 0], 7, 1)


def test_trials_far_longer_are_not_cleaned_and_failed_trials_are_skipped() -> None:
    # Three pieces of 2 steps, 3 agents, all on agent 0 (6 steps): piece 0 to agent 1 fails
    # (DealError), to agent 2 gives 4 steps (kept); piece 1 to agent 0 gives 6 raw steps,
    # 2 more than 4: not cleaned; to agent 1, 2 steps (kept). Piece 2 is on agent 0 and
    # alone there: to 1 or 2 it makes 4 raw steps (kept out by SLACK: 2 more than 2).
    cleaned: list[int] = []

    def run(owner: Sequence[int]) -> JointSteps:
        if owner[0] == 1:
            raise DealError("boxed in")
        loads = [2 * list(owner).count(a) for a in range(3)]
        return [[(a, None) for a in range(3) if loads[a] > t] for t in range(max(loads))]  # type: ignore[misc]

    def clean(steps: JointSteps) -> JointSteps:
        cleaned.append(len(steps))
        return steps

    found = search_owners([0, 0, 0], [0, 1, 2], 3, run, clean, lambda: 0)
    assert (found.owner, found.length, found.moves) == ([2, 1, 0], 2, 2)
    assert cleaned == [6, 4, 2]  # the first run, then only the two trials kept


# Blocksworld: b4 on b1 on b3 on b5, b2 on the table; goal b1 on b4 on b3, b5 on b2.
# Lama-first's plan (14 actions) stacks b1 on b4 while b4 is still on the table and takes
# it off again; action elimination keeps all 14 (each is needed by the plan's own order).
UNSTACKED = """(define (problem blocks-p05) (:domain blocks)
  (:objects b1 b2 b3 b4 b5)
  (:init (on-table b2) (on-table b5) (on b3 b5) (on b1 b3) (on b4 b1) (clear b2) (clear b4)
         (arm-empty))
  (:goal (and (on b1 b4) (on b4 b3) (on b5 b2))))
"""
UNSTACKED_PLAN = (
    "(unstack b4 b1)", "(putdown b4)", "(unstack b1 b3)", "(stack b1 b4)", "(unstack b3 b5)",
    "(putdown b3)", "(pickup b5)", "(stack b5 b2)", "(unstack b1 b4)", "(putdown b1)",
    "(pickup b4)", "(stack b4 b3)", "(pickup b1)", "(stack b1 b4)",
)  # fmt: skip


@pytest.mark.parametrize(("agents", "length"), [(2, 7), (3, 6)])
def test_owner_search_reaches_the_shortest_schedule(
    tmp_path: Path, agents: int, length: int
) -> None:
    # What any schedule needs: b4, b1, b3 come off one after the other (each clears the
    # next), b3 goes down (b4 must go onto it, b5 onto b2), b4 onto it, b1 onto b4: a chain
    # of 6 actions, so 6 steps at least. With 2 agents 6 steps would take (unstack b3 b5) in
    # step 3, by a free arm: the one that took b4 off in step 1 and set it down in step 2
    # (the other took b1 off in step 2). b4 must then be taken up again by step 4, while
    # that arm puts b3 down: by the other arm, which must first set b1 down. So b4 and b1
    # are set down and taken up again, 12 actions with b5's two; but in step 1 only
    # (unstack b4 b1) can act, so 6 steps hold 11 at most: 7 steps. Both are
    # reached, and are shorter than the list schedules without the search (8 and 7: their
    # agents leave b1 for another to take off b4, and the joint clean-up cannot drop the
    # detour).
    task = blocks_task(tmp_path, UNSTACKED)
    request = MethodRequest(task, agents, FAST, BW, sa_plan=sa_result(UNSTACKED_PLAN))
    without = run_plan_deal(request, owner_search=False)
    run = run_plan_deal(request)
    for one in (without, run):
        check_valid_run(task.problem, one, BW)
    assert without.exec_length == length + 1
    assert run.exec_length == length and run.fallback is None
    chosen = next(row for row in run.extra["deal"] if row.get("chosen"))
    assert chosen["improved"] and chosen["moves"] >= 1
    assert "owner search" in run.extra["deal_seconds"]


def test_the_owner_search_keeps_the_walks_links_where_the_deal_needs_them(
    data_root: Path,
) -> None:
    # termes p18 with 2 agents: in the order without walks a ramp goes before a robot has
    # crossed it, so the agents of the free/critical list schedule run into a place they
    # cannot walk to (DealError), and the deal is made with the walks' links kept. The
    # owner search starts from the same deal: it must keep the links too (it failed with
    # "no agent can walk to where the next piece applies" before), and it can only be as
    # short as the deal it starts from or shorter; the outcome re-validates.
    import yaml

    preds = yaml.safe_load((Path(__file__).parents[1] / "conf/domain/termes.yaml").read_text())
    preds = preds["agent_predicates"]
    task = load_task("termes", 18, data_root)
    sa = run_single_agent(MethodRequest(task, planner=FAST))
    plan = sa.planner_calls[0].result
    assert plan.plan is not None
    dealer = Dealer(task.problem, plan.plan, preds)
    with pytest.raises(DealError):  # the timed run of that order, without the walks' links
        dealer._deal(2, "critical", "free", keep_walks=False, steal=False, timed=True)
    dealt = dealer.deal(2, "free", "critical", False)
    improved = dealer.improve(2, "free", "critical", False)
    assert len(improved.schedule) <= len(dealt.schedule)
    run = run_plan_deal(MethodRequest(task, 2, FAST, preds, sa_plan=plan))
    searched = [row for row in run.extra["deal"] if row.get("improved")]
    assert searched and all("error" not in row for row in searched)
    check_valid_run(task.problem, run, preds)


def test_passes_repeat_while_one_keeps_a_move() -> None:
    # Pieces of 1, 1, 3 and 3 steps, 2 agents, all on agent 0 (8 steps), tried in the order
    # 0, 1, 2, 3. First pass: piece 0 to agent 1 (7 / 1: 7), kept; piece 1 (6 / 2: 6), kept;
    # piece 2 (3 / 5: 5), kept; piece 3 to agent 1 (0 / 8), not shorter. A single pass ends
    # at 5 steps, with owners 1, 1, 1, 0. The second pass gives piece 0 back to agent 0
    # (4 / 4: 4), kept, and moves none of the other three (each move makes one side 5 or
    # more); the third keeps nothing: 4 steps, four moves, the shortest for these pieces
    # (1 + 3 on each agent).
    lengths = (1, 1, 3, 3)
    runs: list[list[int]] = []

    def run(owner: Sequence[int]) -> JointSteps:
        runs.append(list(owner))
        loads = [sum(n for n, a in zip(lengths, owner, strict=True) if a == b) for b in (0, 1)]
        return [[(a, None) for a in (0, 1) if loads[a] > t] for t in range(max(loads))]  # type: ignore[misc]

    found = search_owners([0, 0, 0, 0], [0, 1, 2, 3], 2, run, lambda steps: steps, lambda: 0)
    assert (found.owner, found.length, found.moves) == ([0, 1, 1, 0], 4, 4)
    # the first run, then each pass tries every piece once (after a kept move, the next
    # piece): four trials in each of the three passes
    assert len(runs) == 1 + 4 + 4 + 4


def test_the_search_for_more_agents_starts_where_the_one_for_fewer_ended(
    data_root: Path,
) -> None:
    # blocksworld p16, a real SA plan: every deal to 4 agents is longer than where the
    # owner search for 3 agents ended, so the search for 4 starts from there, the fourth
    # arm idle (its row says after = 3), and it finds a shorter schedule than the 3-agent
    # run's outcome: a fourth arm that the search from the 4-agent deals did not use. The
    # schedules re-validate.
    import yaml

    path = Path(__file__).parents[1] / "conf/domain/blocksworld.yaml"
    preds = yaml.safe_load(path.read_text())["agent_predicates"]
    task = load_task("blocksworld", 16, data_root)
    sa = run_single_agent(MethodRequest(task, planner=FAST))
    plan = sa.planner_calls[0].result
    three = run_plan_deal(MethodRequest(task, 3, FAST, preds, sa_plan=plan))
    four = run_plan_deal(MethodRequest(task, 4, FAST, preds, sa_plan=plan))
    for run in (three, four):
        check_valid_run(task.problem, run, preds)
    (search,) = [r for r in four.extra["deal"] if r.get("improved") and r["agents"] == 4]
    assert search["after"] == 3
    deals = [r["exec_length"] for r in four.extra["deal"]
             if r["agents"] == 4 and not r.get("improved") and "exec_length" in r]  # fmt: skip
    assert three.exec_length is not None and four.exec_length is not None
    assert four.exec_length < three.exec_length < min(deals)
    assert search.get("chosen") and search["exec_length"] == four.exec_length
