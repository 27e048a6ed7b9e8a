"""Walking ahead (:mod:`twostep.dealing.timeline`): an agent whose next action cannot apply
yet walks to where it will stand for it, instead of waiting where it is.

A termes task written here (the repository's termes domain): a line of four cells, the
depot at one end. The makespans are derived by hand in the comments; every schedule is
checked by ``check_run`` and by the independent validator on the task's files. Storage (the
IPC sample's domain, a problem of our own) is where agents must not walk ahead.
"""

from __future__ import annotations

import shutil
from itertools import pairwise
from pathlib import Path

from tests.conftest import own_task
from tests.examples import STORAGE_PROBLEM, storage_init
from tests.support.plans import FAST, check_valid_task_run, sa_result
from tests.support.skips import IPC_SAMPLE, needs_ipc_sample
from twostep.dealing import Dealer, ways
from twostep.dealing.timeline import Timeline
from twostep.methods import MethodRequest, run_single_agent
from twostep.methods.plan_deal import run_plan_deal
from twostep.tasks.benchmark import BenchmarkTask, load_task

TERMES = ["at", "has-block"]

# p0 (the depot) - p1 - p2 - p3, all at height 0, the robot on the depot. Goal: p3 two
# blocks high, p2 one. The SA plan: block A onto p3 (standing on p2), block B onto p2
# (standing on p1), then up onto p2 and block C onto p3.
LINE_PLAN = (
    "(create-block p0)", "(move p0 p1 n0)", "(move p1 p2 n0)", "(place-block p2 p3 n0 n1)",
    "(move p2 p1 n0)", "(move p1 p0 n0)",
    "(create-block p0)", "(move p0 p1 n0)", "(place-block p1 p2 n0 n1)", "(move p1 p0 n0)",
    "(create-block p0)", "(move p0 p1 n0)", "(move-up p1 n0 p2 n1)", "(place-block p2 p3 n1 n2)",
)  # fmt: skip


def _line(tmp_path: Path, data_root: Path) -> BenchmarkTask:
    cells = ("p0", "p1", "p2", "p3")
    neighbours = " ".join(f"(neighbor {a} {b}) (neighbor {b} {a})" for a, b in pairwise(cells))
    heights = " ".join(f"(height {c} n0)" for c in cells)
    problem = (
        "(define (problem line) (:domain termes) (:objects n0 n1 n2 - numb "
        f"{' '.join(cells)} - position) (:init {heights} (at p0) (succ n1 n0) (succ n2 n1) "
        f"{neighbours} (is-depot p0)) (:goal (and (height p3 n2) (height p2 n1))))"
    )
    domain = (data_root / "termes" / "domain.pddl").read_text()
    return own_task(tmp_path, "line", domain, problem)


def test_an_agent_with_a_block_waits_beside_the_ramp_not_at_the_depot(
    tmp_path: Path, data_root: Path
) -> None:
    # The three placings form a chain: A needs p2 low (B raises it), C needs p2 and p3
    # raised. A is placed at step 4 at the earliest (create, two moves, place), so B at 5
    # and C at 6: no schedule is shorter than 6, whatever the agents.
    # Three agents, one block each. Walking ahead, C's agent walks to p2 with its block
    # while A and B are placed (standing on p2 as B raises it) and places C at step 6.
    # Without it C's agent waits on the depot until B is placed (step 5): it climbs from
    # p1 (where it may wait, as p1 stays low) onto p2 at 6 and places C at 7.
    task = _line(tmp_path, data_root)
    lengths = {}
    for ahead in (False, True):
        dealer = Dealer(task.problem, LINE_PLAN, TERMES, walks_ahead=ahead)
        lengths[ahead] = {len(dealer.deal(3, w.cut, w.order, w.steal).schedule) for w in ways()}
    assert lengths == {False: {7}, True: {6}}
    request = MethodRequest(task, 3, FAST, TERMES, sa_plan=sa_result(LINE_PLAN))
    run = run_plan_deal(request)
    assert run.exec_length == 6
    check_valid_task_run(task, run, TERMES)
    # the agent that places C stood on p2 before B raised it: its move onto p2 is at height 0
    (placer,) = [a for a, plan in run.plans.items() if "(place-block p2 p3 n1 n2)" in plan]
    assert "(move p1 p2 n0)" in run.plans[placer]
    assert "(move-up p1 n0 p2 n1)" not in run.plans[placer]


def test_two_agents_reach_the_shortest_schedule_either_way(tmp_path: Path, data_root: Path) -> None:
    # Two agents, three blocks: one agent places two, with a trip to the depot between.
    # After A (step 4 at the earliest, on p2) that is 2 moves back, create, 1 move, B at 9,
    # and C at 10 at the earliest; after B (step 5, on p1): 1 move back, create, 1 move, up
    # onto p2, C at 10. So no schedule is shorter than 10, and the other agent has time to
    # walk: walking ahead changes nothing here.
    task = _line(tmp_path, data_root)
    for ahead in (False, True):
        dealer = Dealer(task.problem, LINE_PLAN, TERMES, walks_ahead=ahead)
        lengths = {len(dealer.deal(2, w.cut, w.order, w.steal).schedule) for w in ways()}
        assert lengths == {10}


@needs_ipc_sample
def test_no_walking_ahead_where_moves_change_shared_facts(tmp_path: Path, data_root: Path) -> None:
    # A storage hoist that moves frees the area it leaves and takes the one it enters
    # (``clear``, a shared fact): one walking ahead would stand in another's way. termes
    # moves change the robot's own ``at`` alone.
    (tmp_path / "storage").mkdir()
    shutil.copy(IPC_SAMPLE / "storage" / "domain.pddl", tmp_path / "storage" / "domain.pddl")
    (tmp_path / "storage" / "p01.pddl").write_text(STORAGE_PROBLEM % storage_init())
    storage = load_task("storage", 1, tmp_path)
    sa = run_single_agent(MethodRequest(storage, planner=FAST)).planner_calls[0].result
    assert sa.plan
    termes = _line(tmp_path, data_root)
    for task, plan, predicates, ahead in (
        (storage, list(sa.plan), ["at", "available", "lifting"], False),
        (termes, LINE_PLAN, TERMES, True),
    ):
        dealer = Dealer(task.problem, plan, predicates)
        timeline = Timeline(dealer.walker, dealer.steps, [], {}, dealer.goal, dealer.init)
        assert timeline.walks_ahead is ahead
