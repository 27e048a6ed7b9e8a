"""twostep.dealing.deal: the SA plan's pieces dealt to N agents, several per agent.

Hand-written SA plans give pieces, walks and makespans that can be derived by hand (each
test's comment); every joint schedule is checked by ``check_run`` (our simulator) and by
unified-planning's validator on the N-agent compilation, laid out sequentially.
"""

from __future__ import annotations

import itertools
import shutil
from pathlib import Path

import pytest

from tests.conftest import own_task
from tests.examples import (
    BW,
    STORAGE_PROBLEM,
    TERMES,
    TERMES_PLAN,
    TERMES_TOWER,
    TWO_TOWERS,
    TWO_TOWERS_PLAN,
    storage_init,
)
from tests.support.plans import (
    FAST,
    agent_predicates_of,
    blocks_task,
    check_valid_run,
    copy_task,
    sa_result,
)
from tests.support.skips import IPC_SAMPLE, needs_ipc_sample
from twostep.dealing import (
    Dealer,
    DealError,
    deal_plan,
    eliminate_actions,
    eliminate_joint,
    walks,
)
from twostep.dealing.replay import Replay
from twostep.makespan import ScheduleError
from twostep.methods import MethodRequest, check_run, run_single_agent
from twostep.methods.plan_deal import run_plan_deal
from twostep.methods.portfolio import Portfolio, run_portfolio
from twostep.pddl import Problem
from twostep.planner import PlannerSettings
from twostep.plans.simulate import GroundAction, Grounder
from twostep.tasks.benchmark import BenchmarkTask, load_task
from twostep.verify.validation import validate_plan


def test_two_towers_dealt_to_two_and_four_agents(tmp_path: Path) -> None:
    # Pieces (pickup, stack): b-c, a-b, e-f, d-e; (stack a b) needs (on b c)'s piece done
    # ((clear b) comes back with (stack b c)), (stack d e) needs e-f. The chains b-c and e-f
    # lead the longest paths, so they start first on two agents. N = 2: each agent then
    # finishes its own tower, 4 steps (SA: 8). N = 4: the upper blocks go to the other two
    # agents, which pick them up while the lower ones are stacked: 3 steps.
    task = blocks_task(tmp_path, TWO_TOWERS)
    for agents, length in ((2, 4), (4, 3)):
        deal = deal_plan(task.problem, TWO_TOWERS_PLAN, agents, BW)
        assert deal.walks == 0 and deal.cleaned == 8 and deal.estimate == length
        run = run_plan_deal(
            MethodRequest(task, agents, FAST, BW, sa_plan=sa_result(TWO_TOWERS_PLAN))
        )
        check_valid_run(task.problem, run, BW)
        assert run.exec_length == length and run.fallback is None
        assert run.decomposer == "plan-deal" and len(run.agent_order) == agents


def test_action_elimination_drops_what_the_goal_does_not_need(tmp_path: Path) -> None:
    # (pickup f) (putdown f) at the start and (unstack a b) (stack a b) at the end change
    # nothing the goal needs: the greedy elimination removes both pairs, 12 -> 8 actions.
    task = blocks_task(tmp_path, TWO_TOWERS)
    wasteful = ("(pickup f)", "(putdown f)", *TWO_TOWERS_PLAN, "(unstack a b)", "(stack a b)")
    grounded = Grounder(task.problem).ground_plan(wasteful)
    cleaned = eliminate_actions(task.problem, grounded)
    assert [str(a) for a in cleaned] == list(TWO_TOWERS_PLAN)
    # a plan with nothing to spare is left alone
    assert eliminate_actions(task.problem, cleaned) == cleaned


def test_joint_elimination_uses_each_agents_own_arm(tmp_path: Path) -> None:
    # Two agents. Agent 1 picks e up, parks it on f, takes it back and puts it down before
    # doing the real work. Dropping its first (pickup e) makes (stack e f), (unstack e f)
    # and (putdown e) inapplicable, so they go with it, and the goal still holds: agent 1
    # keeps only its last four actions. Agent 0's chain is needed for the goal and stays.
    task = blocks_task(tmp_path, TWO_TOWERS)
    g = Grounder(task.problem).ground
    joint = [
        (0, g("(pickup b)")), (1, g("(pickup e)")), (0, g("(stack b c)")), (1, g("(stack e f)")),
        (0, g("(pickup a)")), (1, g("(unstack e f)")), (0, g("(stack a b)")),
        (1, g("(putdown e)")), (1, g("(pickup e)")), (1, g("(stack e f)")),
        (1, g("(pickup d)")), (1, g("(stack d e)")),
    ]  # fmt: skip
    kept = eliminate_joint(task.problem, joint, 2, BW)
    assert [(a, str(x)) for a, x in kept] == [
        (0, "(pickup b)"), (0, "(stack b c)"), (0, "(pickup a)"), (0, "(stack a b)"),
        (1, "(pickup e)"), (1, "(stack e f)"), (1, "(pickup d)"), (1, "(stack d e)"),
    ]  # fmt: skip


def test_termes_agents_walk_to_their_pieces(tmp_path: Path, data_root: Path) -> None:
    # Acting actions: base on p2 from p3 [create, place], ramp on p1 [create, place], top
    # [create, place from p1], ramp away [remove, destroy]. In the SA plan's order: agent 0
    # takes the base (walk d->p3, placed at t3); agent 1 the ramp (t1-t2), then the top
    # (create t3, move-up t4, place t5). The ramp-away piece goes to agent 0 (free at t3),
    # which walks back p3->d at t4; its remove deletes (height p1 n1), which the place at
    # t5 reads: remove at t6, destroy at t7. Makespan 7 (SA: 12), and no deal of these
    # pieces to two agents does better: the top needs the base (t3) and an agent holding a
    # block on the ramp, i.e. one that did not build the base (create, ramp t2, create,
    # move-up t4 at the earliest), so it is placed at t5, the ramp removed after it.
    task = copy_task(tmp_path, data_root, "termes", TERMES_TOWER)
    deal = deal_plan(task.problem, TERMES_PLAN, 2, TERMES, cut="free", order="plan")
    assert deal.plans[0] == [
        "(create-block d)", "(move d p3 n0)", "(place-block p3 p2 n0 n1)",
        "(move p3 d n0)", "(remove-block d p1 n1 n0)", "(destroy-block d)",
    ]  # fmt: skip
    assert deal.plans[1] == [
        "(create-block d)", "(place-block d p1 n0 n1)",
        "(create-block d)", "(move-up d n0 p1 n1)", "(place-block p1 p2 n1 n2)",
    ]  # fmt: skip
    assert deal.walks == 3  # d->p3 for the base, up the ramp for the top, p3->d after
    run = run_plan_deal(MethodRequest(task, 2, FAST, TERMES, sa_plan=sa_result(TERMES_PLAN)))
    check_valid_run(task.problem, run, TERMES)
    assert run.exec_length == 7 and run.exact
    assert run.extra["deal"][0] == {  # the one-agent deal: the cleaned SA plan
        "agents": 1, "pieces": 1, "walks": 4, "cleaned_sa_length": 12, "agents_used": 1,
        "exec_length": 12,
    }  # fmt: skip
    assert {(r["cut"], r["order"], r["steal"]) for r in run.extra["deal"] if r["agents"] == 2} == {
        ("free", "critical", False),
        ("holding", "critical", True),
        ("holding", "plan", False),
    }


def test_no_walk_means_the_sa_plan(
    tmp_path: Path, data_root: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # With the walking search allowed no state, agent 0 cannot walk to p3: no deal to two
    # agents, so the one-agent deal is the result (the cleaned SA plan, here the SA plan
    # itself: nothing to drop) and ``fallback`` says why. (The offload in the plan's own
    # order needs no search for the first agent, who walks the plan's own walks, and
    # deals it: with it off here; on below.)
    monkeypatch.setattr(walks, "WALK_LIMIT", 0)
    task = copy_task(tmp_path, data_root, "termes", TERMES_TOWER)
    request = MethodRequest(task, 2, FAST, TERMES, sa_plan=sa_result(TERMES_PLAN))
    dealt = run_plan_deal(request)
    (chosen,) = [row for row in dealt.extra["deal"] if row.get("chosen")]
    assert chosen.get("offloaded") and dealt.fallback is None
    assert dealt.exec_length is not None and dealt.exec_length < len(TERMES_PLAN)
    check_valid_run(task.problem, dealt, TERMES)

    def stuck(*args: object) -> None:
        raise DealError("stuck")

    monkeypatch.setattr(Replay, "in_plan_order", stuck)
    run = run_plan_deal(request)
    assert run.success and run.exec_length == len(TERMES_PLAN)
    assert run.fallback is not None and "walk" in run.fallback
    assert run.agent_order == ["agent0"] and run.plans["agent0"] == list(TERMES_PLAN)
    assert all("error" in row for row in run.extra["deal"] if row["agents"] > 1)


def test_longer_than_sa_falls_back(tmp_path: Path) -> None:
    # One tower of two blocks: a single chain (pickup b, stack b c... here a on b): no
    # overlap, the deal equals SA's length, never longer; with one agent nothing is dealt.
    task = blocks_task(tmp_path, TWO_TOWERS)
    run = run_plan_deal(MethodRequest(task, 1, FAST, BW, sa_plan=sa_result(TWO_TOWERS_PLAN)))
    assert run.exec_length == 8 and run.fallback == "one agent"


def test_an_sa_plan_that_does_not_apply_is_not_dealt(tmp_path: Path) -> None:
    # (stack a b) first: the arm holds nothing yet. The dealer says so in the deal rows
    # (no exception); the outcome is the plan it was given, which check_run rejects, and the
    # run is an error, not a success.
    task = blocks_task(tmp_path, TWO_TOWERS)
    bad = ("(stack a b)", *TWO_TOWERS_PLAN)
    run = run_plan_deal(MethodRequest(task, 2, FAST, BW, sa_plan=sa_result(bad)))
    assert run.extra["deal"] == [
        {"agents": 1, "error": "not a valid run: (stack a b) does not apply"}
    ]
    assert run.fallback == "one agent" and run.plans == {"agent0": list(bad)}
    with pytest.raises(ScheduleError, match=r"\(stack a b\): precondition \(holding a\)"):
        check_run(task.problem, run, BW)
    # ... and it is not reported as solved: no success, no length, the message says why
    assert not run.success and run.status == "error" and run.exec_length is None
    assert run.message == "the SA plan does not apply: not a valid run: (stack a b) does not apply"


def test_portfolio_keeps_the_deal_when_it_is_shortest(tmp_path: Path) -> None:
    task = blocks_task(tmp_path, TWO_TOWERS)
    run = run_portfolio(
        MethodRequest(task, 2, FAST, BW, sa_plan=sa_result(TWO_TOWERS_PLAN)), Portfolio()
    )
    check_valid_run(task.problem, run, BW)
    rows = run.extra["candidates"]
    (deal,) = [r for r in rows if r["decomposer"] == "plan-deal"]  # with N agents only
    assert deal["agents"] == 2 and deal["exec_length"] == 4
    assert run.exec_length == min(r["exec_length"] for r in rows if r["exec_length"])


def test_walk_links_kept_when_no_walk_exists(data_root: Path) -> None:
    # termes p13 with 4 agents: in the walk-free order a ramp goes before an agent has
    # crossed it and the replay finds no walk (this failed before the retry); with the
    # walks' links kept the deal succeeds and re-validates.
    import yaml

    preds = yaml.safe_load((Path(__file__).parents[1] / "conf/domain/termes.yaml").read_text())
    preds = preds["agent_predicates"]
    task = load_task("termes", 13, data_root)
    sa = run_single_agent(MethodRequest(task, planner=FAST))
    run = run_plan_deal(MethodRequest(task, 4, FAST, preds, sa_plan=sa.planner_calls[0].result))
    assert run.fallback is None and run.exec_length is not None
    assert sa.exec_length is not None and run.exec_length < sa.exec_length
    check_valid_run(task.problem, run, preds)


@pytest.mark.parametrize("agents", [2, 4])
def test_real_sa_plans_deal_and_validate(data_root: Path, agents: int) -> None:
    # Every domain's first task, a real SA plan: the dealt schedule re-validates in our
    # simulator and in unified-planning's, and is never longer than SA.
    import yaml

    for domain in ("barman", "blocksworld", "grippers", "termes", "tyreworld"):
        preds = yaml.safe_load(
            (Path(__file__).parents[1] / "conf" / "domain" / f"{domain}.yaml").read_text()
        )["agent_predicates"]
        task = load_task(domain, 1, data_root)
        sa = run_single_agent(MethodRequest(task, planner=FAST))
        run = run_plan_deal(
            MethodRequest(task, agents, FAST, preds, sa_plan=sa.planner_calls[0].result)
        )
        assert run.success and run.exec_length is not None and sa.exec_length is not None
        assert run.exec_length <= sa.exec_length
        if run.fallback is None:
            check_valid_run(task.problem, run, preds)


def _hubs(task: BenchmarkTask) -> int:
    return sum(1 for kind in task.problem.all_objects.values() if kind == "hub")


@pytest.mark.parametrize("task_id", [1, 2, 4])
def test_tyreworld_deals_reach_the_one_jack_floor(data_root: Path, task_id: int) -> None:
    # With one jack, any schedule of a W-hub task takes at least 6W + 6 steps, whatever N:
    # each hub needs jack-up, undo, remove-wheel, put-on-wheel, do-up, jack-down, each
    # using the fact the one before it gives (do-up fastens the hub, so the wheel goes on
    # first; jack-down needs do-up's not-on-ground still true), and the next jack-up needs
    # (have jack), which only jack-down gives back: 6W steps one after another. Before the
    # first jack-up: open the boot, fetch the wrench, loosen the nut (it needs the hub on
    # the ground). After the last jack-down: tighten that nut, put the wrench away, close
    # the boot. So the floor is 6W + 6 and it does not fall with N: the deal reaches it.
    # That chain is the longest of the plan's order, so the owner search stops at once.
    task = load_task("tyreworld", task_id, data_root)
    hubs = _hubs(task)
    sa = run_single_agent(MethodRequest(task, planner=FAST))
    assert sa.exec_length is not None
    assert sa.planner_calls[0].result.plan is not None
    dealer = Dealer(task.problem, sa.planner_calls[0].result.plan, [])
    assert dealer.chain("free") == dealer.chain("holding") == 6 * hubs + 6
    for agents in (2, 4):
        run = run_plan_deal(
            MethodRequest(task, agents, FAST, [], sa_plan=sa.planner_calls[0].result)
        )
        check_valid_run(task.problem, run, [])
        assert run.exec_length == 6 * hubs + 6, (agents, run.exec_length)
        searched = [row for row in run.extra["deal"] if row.get("improved")]
        assert searched and all(row["moves"] == 0 for row in searched)


def test_the_deal_does_not_depend_on_the_hash_seed(data_root: Path, tmp_path: Path) -> None:
    # termes p02 has walks of equal length over different cells: the walking search must
    # pick the same one in every process (Python's set order changes with PYTHONHASHSEED;
    # before the fix three seeds gave three different deals of the same SA plan).
    import json
    import os
    import subprocess
    import sys

    task = load_task("termes", 2, data_root)
    sa = run_single_agent(MethodRequest(task, planner=FAST)).planner_calls[0].result
    assert sa.plan is not None
    (tmp_path / "plan.json").write_text(json.dumps(list(sa.plan)))
    script = (
        "import json, sys\n"
        "from pathlib import Path\n"
        "from twostep.tasks.benchmark import load_task\n"
        "from twostep.dealing import deal_plan\n"
        "task = load_task('termes', 2, Path(sys.argv[1]))\n"
        "plan = json.loads(Path(sys.argv[2]).read_text())\n"
        "print(json.dumps(deal_plan(task.problem, plan, 3, ['at', 'has-block']).plans))\n"
    )
    outputs = {
        subprocess.run(
            [sys.executable, "-c", script, str(data_root), str(tmp_path / "plan.json")],
            capture_output=True, text=True, check=True,
            env={**os.environ, "PYTHONHASHSEED": seed},
        ).stdout
        for seed in ("1", "2", "3")
    }  # fmt: skip
    assert len(outputs) == 1 and json.loads(outputs.pop())


# ---------------------------------------------- walking that changes the environment

# Our own small domains. rounds: a walker marks every spot it reaches as seen (a fact only
# ever added: the moves may still be used as walks). hall: a robot paints the cells next
# to it; a cell is empty while nobody stands on it and it is not painted (a step changes
# the shared ``empty`` facts, as a hoist changes storage's ``clear``).
ROUNDS = """(define (domain rounds)
  (:requirements :strips :typing)
  (:types spot)
  (:predicates (here ?s - spot) (link ?a ?b - spot) (seen ?s - spot))
  (:action go
    :parameters (?a ?b - spot)
    :precondition (and (here ?a) (link ?a ?b))
    :effect (and (here ?b) (not (here ?a)) (seen ?b))))"""
HALL = """(define (domain hall)
  (:requirements :strips :typing)
  (:types cell)
  (:predicates (at ?c - cell) (empty ?c - cell) (adj ?a ?b - cell) (painted ?c - cell))
  (:action step
    :parameters (?a ?b - cell)
    :precondition (and (at ?a) (adj ?a ?b) (empty ?b))
    :effect (and (at ?b) (not (at ?a)) (empty ?a) (not (empty ?b))))
  (:action paint
    :parameters (?a ?b - cell)
    :precondition (and (at ?a) (adj ?a ?b) (empty ?b))
    :effect (and (painted ?b) (not (empty ?b)))))"""


def _line(names: list[str], relation: str) -> str:
    return " ".join(
        f"({relation} {a} {b}) ({relation} {b} {a})" for a, b in itertools.pairwise(names)
    )


def test_walks_that_mark_spots_split_a_round(tmp_path: Path) -> None:
    # Nine spots in a line, the walker on the middle one; every spot must be seen. The SA
    # plan (by hand) goes to one end and back across to the other: 12 moves. Each move is
    # a piece of its own (no order between them); with two agents one takes the left
    # half and the other the right one, four moves each: 4 steps. The moves the SA plan
    # made back across the middle are needed by nobody then (the joint clean-up drops
    # them), and more agents cannot do better (4 moves to reach an end).
    spots = [f"s{i}" for i in range(9)]
    problem = (
        f"(define (problem line) (:domain rounds) (:objects {' '.join(spots)} - spot) "
        f"(:init (here s4) (seen s4) {_line(spots, 'link')}) "
        f"(:goal (and {' '.join(f'(seen {s})' for s in spots)})))"
    )
    task = own_task(tmp_path, "rounds", ROUNDS, problem)
    plan = [f"(go s{i} s{i - 1})" for i in range(4, 0, -1)]
    plan += [f"(go s{i} s{i + 1})" for i in range(8)]
    for agents in (2, 3):
        run = run_plan_deal(
            MethodRequest(task, agents, FAST, ["here"], sa_plan=sa_result(tuple(plan)))
        )
        check_valid_run(task.problem, run, ["here"])
        assert run.exec_length == 4 and run.extra["agents_used"] == 2 and run.fallback is None


def _hall_task(tmp_path: Path, length: int, robot: int, goal: str) -> BenchmarkTask:
    """The hall domain on a corridor of cells c0..c<length-1>, the robot on c<robot>, every
    other cell empty."""
    cells = [f"c{i}" for i in range(length)]
    empty = " ".join(f"(empty {c})" for i, c in enumerate(cells) if i != robot)
    problem = (
        f"(define (problem corridor) (:domain hall) (:objects {' '.join(cells)} - cell) "
        f"(:init (at c{robot}) {empty} {_line(cells, 'adj')}) (:goal (and {goal})))"
    )
    return own_task(tmp_path, "hall", HALL, problem)


def test_plans_of_agents_that_start_alike_are_stitched_with_walks(tmp_path: Path) -> None:
    # TwoStep's agents each start on c3. The helper paints c0 from c1; the main agent's
    # plan starts with a step from c3, where one agent no longer stands: the stitch walks
    # it back first (c1 -> c2 -> c3), and the result is one plan the task accepts.
    task = _hall_task(tmp_path, 7, 3, "(painted c0) (painted c6)")
    helper = ["(step c3 c2)", "(step c2 c1)", "(paint c1 c0)"]
    main = ["(step c3 c4)", "(step c4 c5)", "(paint c5 c6)"]
    stitched = walks.stitch(task.problem, [helper, main], ["at"])
    assert stitched == [*helper, "(step c1 c2)", "(step c2 c3)", *main]
    assert validate_plan(task.problem, stitched).valid
    # plans that apply one after the other come back as they are
    assert walks.stitch(task.problem, [main, ["(step c5 c4)"]], ["at"]) == [*main, "(step c5 c4)"]
    # a helper that paints its way into c0 boxes the agent in: no walk back to c3
    boxed = ["(step c3 c2)", "(step c2 c1)", "(step c1 c0)", "(paint c0 c1)"]
    with pytest.raises(DealError, match="no walk"):
        walks.stitch(task.problem, [boxed, main], ["at"])


def test_walks_that_change_shared_facts_deal(tmp_path: Path) -> None:
    # Seven cells in a corridor, the robot on the middle one (c3); paint both ends' two
    # cells. The SA plan (by hand): left two steps, paint c0, step back, paint c1, right
    # three steps, paint c6, step back, paint c5: 11 actions. A step changes the shared
    # ``empty`` facts, so walks do too. Two agents: one paints the left end, the other
    # the right end, 5 steps each at once (step, step, paint, step back, paint): 5.
    task = _hall_task(tmp_path, 7, 3, "(painted c0) (painted c1) (painted c5) (painted c6)")
    plan = (
        "(step c3 c2)", "(step c2 c1)", "(paint c1 c0)", "(step c1 c2)", "(paint c2 c1)",
        "(step c2 c3)", "(step c3 c4)", "(step c4 c5)", "(paint c5 c6)", "(step c5 c4)",
        "(paint c4 c5)",
    )  # fmt: skip
    dealer = Dealer(task.problem, plan, ["at"])
    walking = [str(a) for a, w in zip(dealer.cleaned, dealer.walking, strict=True) if w]
    assert walking == [a for a in plan if a.startswith("(step")]  # steps walk, paints act
    for agents in (2, 4):
        run = run_plan_deal(MethodRequest(task, agents, FAST, ["at"], sa_plan=sa_result(plan)))
        check_valid_run(task.problem, run, ["at"])
        assert run.exec_length == 5 and run.extra["agents_used"] == 2 and run.fallback is None


def test_walks_that_reach_goal_facts_are_walked_at_the_end(tmp_path: Path) -> None:
    # The hall corridor again, but the cells the robot paints from must end up empty:
    # goal (painted c0) (painted c6) (empty c1) (empty c5). The SA plan (by hand): left
    # two steps, paint c0, step off c1; right three steps, paint c6, step off c5: 10
    # actions, 8 of them steps. The steps off c1 and c5 lead to no acting action, so no
    # walk to a piece brings them back (before the fix no deal reached the goal and the
    # run fell back to the SA plan). Two agents: each paints one end and steps off the
    # cell it painted from (step, step, paint, step back): 4 steps.
    task = _hall_task(tmp_path, 7, 3, "(painted c0) (painted c6) (empty c1) (empty c5)")
    plan = (
        "(step c3 c2)", "(step c2 c1)", "(paint c1 c0)", "(step c1 c2)", "(step c2 c3)",
        "(step c3 c4)", "(step c4 c5)", "(paint c5 c6)", "(step c5 c4)",
    )  # fmt: skip
    for agents in (2, 3):
        run = run_plan_deal(MethodRequest(task, agents, FAST, ["at"], sa_plan=sa_result(plan)))
        check_valid_run(task.problem, run, ["at"])
        assert run.fallback is None and run.extra["agents_used"] == 2
        assert run.exec_length == 4


def test_an_sa_plan_of_walks_alone_is_dealt(tmp_path: Path) -> None:
    # The robot only has to leave the middle cell: goal (empty c3). The SA plan is one
    # step, a walk: no acting action, no piece. The deal walks an agent off at the end;
    # one step, as the SA plan (before the fix: no deal reached the goal).
    task = _hall_task(tmp_path, 3, 1, "(empty c1)")
    run = run_plan_deal(MethodRequest(task, 2, FAST, ["at"], sa_plan=sa_result(("(step c1 c0)",))))
    assert run.exec_length == 1 and run.fallback is not None
    assert "no deal shorter" in run.fallback  # dealt, just not shorter
    assert all("error" not in row for row in run.extra["deal"])
    check_valid_run(task.problem, run, ["at"])


# lift: our own elevator. ``halt`` has only conditional effects (riders whose target this
# is get off and are done, riders waiting here who are not done get in); a rider inside
# is what the lift carries, not where it is, though ``halt`` both adds and deletes it.
LIFT = """(define (domain lift)
  (:requirements :typing :conditional-effects :negative-preconditions)
  (:types rider level)
  (:predicates (at ?l - level) (next ?a ?b - level) (inside ?r - rider)
               (start ?r - rider ?l - level) (target ?r - rider ?l - level) (done ?r - rider))
  (:action move
    :parameters (?a ?b - level)
    :precondition (and (at ?a) (next ?a ?b))
    :effect (and (at ?b) (not (at ?a))))
  (:action halt
    :parameters (?l - level)
    :precondition (at ?l)
    :effect (and
      (forall (?r - rider) (when (and (inside ?r) (target ?r ?l)) (and (not (inside ?r)) (done ?r))))
      (forall (?r - rider) (when (and (start ?r ?l) (not (done ?r))) (inside ?r))))))"""


def test_a_lift_with_conditional_effects_deals(tmp_path: Path) -> None:
    # Five levels l0..l4, every lift at l2; rider a waits at l1 for l0, rider b at l3 for
    # l4. The SA plan (by hand): down to l1, halt (a gets in), down, halt (a done), back up
    # to l3, halt (b in), up, halt (b done): 10 actions. The halts that let a rider in
    # change what the lift carries, not where it is: they are acting actions, and the
    # rider's two halts are one piece (the lift holds a between them). Left without the
    # walks between them, the halts do not apply from the initial state (halt l0 with the
    # lift at l2): the order is read from the plan as it ran. Two agents: one lift takes
    # a (move, halt, move, halt), the other b, at once: 4 steps. No schedule is shorter
    # (a rider's two halts and two moves are one lift's), so three agents give 4 too.
    levels = [f"l{i}" for i in range(5)]
    problem = (
        f"(define (problem two-riders) (:domain lift) "
        f"(:objects {' '.join(levels)} - level a b - rider) "
        f"(:init (at l2) {_line(levels, 'next')} (start a l1) (target a l0) "
        "(start b l3) (target b l4)) (:goal (and (done a) (done b))))"
    )
    task = own_task(tmp_path, "lift", LIFT, problem)
    plan = (
        "(move l2 l1)", "(halt l1)", "(move l1 l0)", "(halt l0)", "(move l0 l1)",
        "(move l1 l2)", "(move l2 l3)", "(halt l3)", "(move l3 l4)", "(halt l4)",
    )  # fmt: skip
    preds = ["at", "inside"]
    dealer = Dealer(task.problem, plan, preds)
    walking = [str(a) for a, w in zip(dealer.cleaned, dealer.walking, strict=True) if w]
    assert walking == [a for a in plan if a.startswith("(move")]  # every halt acts
    assert dealer.pieces("free", False)[0] == [[1, 3], [7, 9]]  # a's halts, b's halts
    for agents in (2, 3):
        run = run_plan_deal(MethodRequest(task, agents, FAST, preds, sa_plan=sa_result(plan)))
        check_valid_run(task.problem, run, preds)
        assert run.exec_length == 4 and run.extra["agents_used"] == 2 and run.fallback is None


# ---------------------------------------------- action elimination against a plain greedy


def plain_greedy(
    problem: Problem, joint: list[tuple[int, GroundAction]], agents: int, preds: list[str]
) -> list[tuple[int, GroundAction]]:
    """Greedy action elimination written out plainly over sets of facts (no shortcuts): drop
    an action and every later one that no longer applies while the goal still holds."""

    def run(steps: list[tuple[int, GroundAction]]) -> tuple[list[tuple[int, GroundAction]], bool]:
        env = {f for f in problem.init if f[0] not in preds}
        own = [{f for f in problem.init if f[0] in preds} for _ in range(agents)]
        kept = []
        for a, action in steps:
            state = env | own[a]
            if action.applicable(state):
                state = (state - action.delete) | action.add
                env = {f for f in state if f[0] not in preds}
                own[a] = {f for f in state if f[0] in preds}
                kept.append((a, action))
        return kept, all(problem.goal.holds(frozenset(env | mine)) for mine in own)

    steps = list(joint)
    i = 0
    while i < len(steps):
        kept, reached = run(steps[:i] + steps[i + 1 :])
        if reached:
            steps = kept
        else:
            i += 1
    return steps


@pytest.mark.parametrize(("domain", "task_id"), [("blocksworld", 9), ("barman", 1), ("termes", 1)])
def test_elimination_agrees_with_the_plain_greedy(
    data_root: Path, domain: str, task_id: int
) -> None:
    # The SA plan alone, then (termes) the SA plan run by agent 0 while agent 1 wanders
    # about (random walks, interleaved at random): the same actions are dropped as by the
    # plain greedy, and every wandering step goes.
    import random

    preds = {"blocksworld": BW, "barman": ["handempty", "holding"], "termes": TERMES}[domain]
    task = load_task(domain, task_id, data_root)
    problem = task.problem
    plan = Grounder(problem).ground_plan(
        run_single_agent(MethodRequest(task, planner=FAST)).plans["agent0"]
    )
    assert eliminate_actions(problem, plan) == [
        a for _, a in plain_greedy(problem, [(0, a) for a in plan], 1, preds)
    ]
    rng = random.Random(task_id)
    walker = Dealer(problem, [str(a) for a in plan], preds).walker
    space = walker.space
    env, own = space.bits(problem.init)
    owns = [own, own]
    joint: list[tuple[int, GroundAction]] = []
    for action in plan:
        while rng.random() < 0.5:  # agent 1 moves, where it can
            moves = walker.successors(env, owns[1])
            if not moves:
                break
            move = rng.choice(moves)
            env, owns[1] = move.apply(env, owns[1])
            joint.append((1, move.action))
        env, owns[0] = space.step(action).apply(env, owns[0])
        joint.append((0, action))
    kept = eliminate_joint(problem, joint, 2, preds)
    assert kept == plain_greedy(problem, joint, 2, preds)
    assert all(a == 0 for a, _ in kept)


# ---------------------------------------------- never longer with more agents

MONOTONE_SLICE = [
    ("blocksworld", 12),
    ("barman", 3),
    ("grippers", 9),
    ("termes", 1),
    ("tyreworld", 3),
]


def lengths_over_n(
    task: BenchmarkTask, preds: list[str], independent: bool, planner: PlannerSettings = FAST
) -> list[int]:
    """The SA plan's length, then plan-deal's with 2, 3 and 4 agents (each re-validated)."""
    sa = run_single_agent(MethodRequest(task, planner=planner))
    assert sa.exec_length is not None, (task.domain_name, task.task_id, sa.message)
    lengths = [sa.exec_length]
    for agents in (2, 3, 4):
        run = run_plan_deal(
            MethodRequest(task, agents, planner, preds, sa_plan=sa.planner_calls[0].result)
        )
        if independent:
            check_valid_run(task.problem, run, preds)
        else:
            check_run(task.problem, run, preds)
        assert run.exec_length is not None and run.extra["agents_used"] <= agents
        lengths.append(run.exec_length)
    return lengths


@pytest.mark.parametrize(("domain", "task_id"), MONOTONE_SLICE)
def test_never_longer_with_more_agents(data_root: Path, domain: str, task_id: int) -> None:
    # N agents may leave one idle, so the deal to N-1 agents is one of N's candidates.
    lengths = lengths_over_n(
        load_task(domain, task_id, data_root), agent_predicates_of(domain), True
    )
    assert lengths == sorted(lengths, reverse=True)


@pytest.mark.slow
@pytest.mark.timeout(3600)  # 100 SA plans and 300 runs: minutes, more on a busy machine
def test_never_longer_with_more_agents_on_all_100_tasks(data_root: Path) -> None:
    # Every task of the five domains, N = 1..4; every schedule re-validated by check_run.
    # The largest termes tasks take lama-first 10-20 s alone, so the SA plan has 120 s.
    worse = []
    patient = PlannerSettings("lama-first", 120)
    for domain in ("barman", "blocksworld", "grippers", "termes", "tyreworld"):
        for task_id in range(1, 21):
            task = load_task(domain, task_id, data_root)
            lengths = lengths_over_n(task, agent_predicates_of(domain), False, patient)
            if lengths != sorted(lengths, reverse=True):
                worse.append((domain, task_id, lengths))
    assert not worse


# ---------------------------------------------- real domains the generators never saw


@needs_ipc_sample
@pytest.mark.slow
def test_ipc_sample_domains_deal_to_two_agents(tmp_path: Path) -> None:
    # Every sample domain with one acting agent (agents.yaml), storage (agent facts: at,
    # available, lifting; moving changes the shared ``clear``) and floortile (two robots,
    # each agent a copy of both; moving changes ``clear`` too): plan-deal with two agents
    # deals, its schedule is shorter than the SA plan, re-validates (check_run) and is valid
    # for the independent checkers on the original files (Fast Downward's translator with
    # a simulator of its own, and unified-planning in an N-agent formulation of its own).
    import yaml

    from checkers import IndependentValidator

    cases = dict(yaml.safe_load((IPC_SAMPLE / "agents.yaml").read_text()))
    cases["floortile-sat11-strips"] = ["robot-at", "robot-has"]
    (tmp_path / "storage").mkdir()
    shutil.copy(IPC_SAMPLE / "storage" / "domain.pddl", tmp_path / "storage" / "domain.pddl")
    (tmp_path / "storage" / "p01.pddl").write_text(STORAGE_PROBLEM % storage_init())
    tasks = {name: load_task(name, 1, IPC_SAMPLE) for name in cases}
    tasks["storage"] = load_task("storage", 1, tmp_path)
    cases["storage"] = ["at", "available", "lifting"]
    for name, task in tasks.items():
        sa = run_single_agent(MethodRequest(task, planner=FAST))
        run = run_plan_deal(
            MethodRequest(task, 2, FAST, cases[name], sa_plan=sa.planner_calls[0].result)
        )
        assert sa.exec_length is not None and run.exec_length is not None, name
        assert run.fallback is None and run.extra["agents_used"] == 2, (name, run.fallback)
        assert run.exec_length < sa.exec_length, name
        check_run(task.problem, run, list(cases[name]))
        verdict = IndependentValidator(task.domain_path, task.problem_path).check_schedule(
            run.agent_order, run.plans, run.schedule, list(cases[name])
        )
        assert verdict.valid, (name, verdict)
        # unified-planning's reader rejects storage's ``either`` in a predicate declaration:
        # there the grounded-task simulator alone checks, as in tests/test_conformance.py
        readers = "grounded-task simulator" + ("" if name == "storage" else " + unified-planning")
        assert verdict.checkers.startswith(readers), (name, verdict.checkers)


@needs_ipc_sample
def test_a_deal_stuck_in_every_replay_is_offloaded() -> None:
    # openstacks p01 with two agents (agent facts: stacks-avail): every way's replay gets
    # stuck (no agent can walk to where a piece applies); offloading pieces from the SA
    # plan's own run to the second agent, one at a time where the run stays valid and gets
    # shorter, deals it. The schedule is shorter than the cleaned SA plan and valid for
    # the independent checkers on the original files.
    from checkers import IndependentValidator

    preds = ["stacks-avail"]
    task = load_task("openstacks-sat08-adl", 1, IPC_SAMPLE)
    sa = run_single_agent(MethodRequest(task, planner=FAST))
    run = run_plan_deal(MethodRequest(task, 2, FAST, preds, sa_plan=sa.planner_calls[0].result))
    (chosen,) = [row for row in run.extra["deal"] if row.get("chosen")]
    assert chosen["agents"] == 2 and chosen.get("offloaded") is True
    assert run.fallback is None and run.exec_length is not None
    assert run.exec_length < chosen["cleaned_sa_length"]
    check_run(task.problem, run, preds)
    verdict = IndependentValidator(task.domain_path, task.problem_path).check_schedule(
        run.agent_order, run.plans, run.schedule, preds
    )
    assert verdict.valid, verdict


# Sample domains beyond agents.yaml, with agent predicates read from their domain files
# (the acting object's own state, none shared with other objects): their p01 leaves work
# to a second agent.
BEYOND_YAML = {
    "depot": ["available", "lifting"],
    "rovers": ["at"],
    "elevators-sat08-strips": ["lift-at", "boarded", "passengers"],
    "citycar-sat14-adl": ["at_car_jun", "at_car_road", "starting"],
}
# ... and p01s whose SA plan ends on walks that reach goal facts (zenotravel's one flight,
# tpp's unload counted as a move): before the closing walk no deal reached the goal.
GOAL_BY_WALKS = {"zenotravel": ["fuel-level", "in"], "tpp": ["at", "loaded"]}


@needs_ipc_sample
@pytest.mark.slow
def test_ipc_sample_domains_beyond_agents_yaml_deal() -> None:
    for name, preds in {**BEYOND_YAML, **GOAL_BY_WALKS}.items():
        task = load_task(name, 1, IPC_SAMPLE)
        sa = run_single_agent(MethodRequest(task, planner=FAST))
        assert sa.exec_length is not None, name
        for agents in (2, 3):
            run = run_plan_deal(
                MethodRequest(task, agents, FAST, preds, sa_plan=sa.planner_calls[0].result)
            )
            check_valid_run(task.problem, run, preds)
            assert run.exec_length is not None and run.exec_length <= sa.exec_length
            if name in BEYOND_YAML:
                assert run.fallback is None and run.extra["agents_used"] >= 2, (name, agents)
                assert run.exec_length < sa.exec_length, (name, agents)
            else:  # every way deals, though no deal is shorter than one flight or 5 steps
                dealt = [r for r in run.extra["deal"] if r["agents"] > 1]
                assert all("error" not in r for r in dealt), (name, agents, run.fallback)


# ------------------------------------------------ bits against the grounded model itself


def test_bits_agree_with_the_grounded_model_on_axioms_and_conditional_effects() -> None:
    # shelf: ``take`` needs the derived (not (busy)), ``drop-all`` has conditional effects
    # under a forall; the bits must say what the grounded model says in every state either
    # agent can reach (breadth-first over all of them, from the task's own actions).
    from tests.examples import SHELF, SHELF_PROBLEM
    from twostep.dealing.encoding import FactSpace
    from twostep.pddl import parse_problem

    problem = parse_problem(SHELF, SHELF_PROBLEM)
    space = FactSpace(problem, ["holding"], ())
    actions = sorted(problem.grounded.actions.values(), key=str)
    steps = [space.step(a) for a in actions]
    assert {str(s) for s in steps if not s.exact} >= {"(take a)", "(drop-all)"}
    goal = space.goal()
    start = problem.close(problem.init)  # the states themselves, run by the grounded model
    seen, queue = {start}, [start]
    while queue:
        state = queue.pop()
        env, own = space.bits(state)
        assert goal.holds(env, [own]) == problem.goal.holds(state)
        for action, step in zip(actions, steps, strict=True):
            assert step.applicable(env, own) == action.applicable(state), (action, state)
            if action.applicable(state):
                after = action.apply(state)
                assert step.apply(env, own) == space.bits(after), (action, state)
                if after not in seen:
                    seen.add(after)
                    queue.append(after)
    assert len(seen) > 8  # objects on the shelf, held, in the bin: many states were checked


@needs_ipc_sample
def test_a_walk_inside_another_piece_is_offloaded_in_plan_order(tmp_path: Path) -> None:
    # storage, one depot, 8 crates, 3 hoists (bench/bench_deal_generated.py, seed 1): the
    # SA plan has hoist1 lift a crate out of hoist0's way, hoist0 pass, and hoist1 put the
    # crate back. Replaying whole pieces gets stuck for every way and owner, even with
    # every piece the first agent's (hoist0 must pass in the middle of hoist1's piece), so
    # plan-deal with 2 agents used to give the cleaned SA plan. The offload now starts from
    # the plan's own run, action by action in its order, and hands pieces on from there:
    # two agents deal it, shorter than SA, and the schedule re-validates (check_run, and
    # the independent validator on the files).
    from checkers import IndependentValidator
    from twostep.generators.ipc_sample import gen_storage

    folder = tmp_path / "storage"
    folder.mkdir()
    shutil.copy(IPC_SAMPLE / "storage" / "domain.pddl", folder / "domain.pddl")
    (folder / "p01.pddl").write_text(gen_storage(1, 8, 3, 1).text)
    task = load_task("storage", 1, tmp_path)
    preds = ["at", "available", "lifting"]
    sa = run_single_agent(MethodRequest(task, planner=FAST))
    assert sa.exec_length is not None
    run = run_plan_deal(MethodRequest(task, 2, FAST, preds, sa_plan=sa.planner_calls[0].result))
    (chosen,) = [row for row in run.extra["deal"] if row.get("chosen")]
    assert run.fallback is None and chosen["agents_used"] == 2 and chosen.get("offloaded")
    assert run.exec_length is not None and run.exec_length < sa.exec_length
    check_run(task.problem, run, preds)
    verdict = IndependentValidator(task.domain_path, task.problem_path).check_schedule(
        run.agent_order, run.plans, run.schedule, preds
    )
    assert verdict.valid, verdict
