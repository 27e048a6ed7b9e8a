"""plan-deal on real IPC domains the project never tuned for, and on the sample's agents.yaml.

For each domain of the IPC sample (read in place, ``--sample``, default ../shared/ipc-sample)
and the agent predicates chosen below from its domain file (the facts that say what the
acting object's own state is, none shared with other objects), or given by the sample's
``agents.yaml`` (``--agents-file``), the SA plan (lama-first, ``--time-limit`` s) is dealt
to N = 2 and 3 agents (``--agents``) by plan-deal. Every schedule, a fallback to the SA plan
included, is re-validated twice: by ``check_run`` (our simulator) and by the independent
validator on the original files (``checkers``: Fast Downward's grounding run by a
simulator of its own, and unified-planning's N-agent formulation where its reader accepts
the files; the column names the checkers that read them).

Prints one row per domain, task, agent predicates and N: SA length, plan-deal length, the
fallback reason if any, both verdicts, the dealing CPU seconds (every phase after the SA
plan, scoring included). A crash (an exception out of plan-deal) or a deal that takes more
than ``--deal-limit`` s is a row too. Domains whose SA plan takes longer than the limit are
skipped. ``--every-problem`` deals every problem file of each domain folder (any file name),
not only p01.

    .venv/bin/python bench/bench_deal_ipc.py --json docs/bench/deal_ipc.json
    .venv/bin/python bench/bench_deal_ipc.py --sample DIR --domains storage \\
        termes-sat18-strips --agents 2 3 4 --no-own --every-problem
    .venv/bin/python bench/bench_deal_ipc.py --sample DIR --domains ferry tsp --no-own

The last deals further real domains (a scratch folder per domain, ``docs/bench/deal_ipc_extra.json``).
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from checkers import IndependentValidator
from evaluation.deal_checks import (
    deal_seconds,
    deal_within,
    fallback_text,
    independent_verdict,
    our_verdict,
)
from tools import record
from twostep.methods import MethodRequest, run_single_agent
from twostep.planner import PlannerSettings
from twostep.tasks.benchmark import BenchmarkTask, load_task
from twostep.util.files import read_yaml_file

REPO = Path(__file__).resolve().parent.parent
SAMPLE = REPO.parent / "shared" / "ipc-sample"
# Agent predicates per domain, read from each domain file: the acting object's own state.
# Where several objects of the agent's kind exist (rovers, satellites, elevators, hoists),
# each agent has its own copy of all of them, as floortile's agents have both robots.
# A predicate shared by the agents' objects and others (depot's, driverlog's, zenotravel's,
# transport's, nomystery's and sokoban's ``at``, which also places crates, packages,
# persons or stones) gives each agent its own copy of where the cargo is: the compilation
# reads it so, and the second row of such a domain probes that reading. airport's second
# row makes the goal (is-parked) an agent fact, which every agent must then reach.
ROVER = ["at", "have_soil_analysis", "have_rock_analysis", "have_image", "calibrated"]
ROVER += ["empty", "full"]  # its store
CASES: dict[str, list[list[str]]] = {
    "depot": [["available", "lifting"], ["at", "available", "lifting"]],
    "driverlog": [["driving"], ["at", "driving"]],
    "rovers": [["at"], ROVER],
    "satellite": [["pointing", "power_avail", "power_on", "calibrated"]],
    "zenotravel": [["fuel-level", "in"], ["at", "fuel-level", "in"]],
    "tpp": [["at", "loaded"]],
    "transport-sat08-strips": [["in", "capacity"], ["at", "in", "capacity"]],
    "nomystery-sat11-strips": [["in", "fuel"], ["at", "in", "fuel"]],
    "elevators-sat08-strips": [["lift-at", "boarded", "passengers"]],
    "miconic-simpleadl": [["lift-at", "boarded"]],
    "storage": [["at", "available", "lifting"]],
    "airport-adl": [
        ["at-segment", "facing", "airborne", "is-moving", "is-pushing"],
        ["at-segment", "facing", "airborne", "is-moving", "is-pushing", "is-parked"],
    ],
    "sokoban-sat08-strips": [["at"]],
    "citycar-sat14-adl": [["at_car_jun", "at_car_road", "starting"]],
    "childsnack-sat14-strips": [["at"]],
    "floortile-sat11-strips": [["robot-at", "robot-has", "free-color"]],
    # no acting agent in these: robustness probes (derived predicates that read an agent
    # predicate become agent facts too; conditional effects under quantifiers)
    "psr-middle": [["closed"]],
    "philosophers": [["at-process"]],
    "schedule": [["busy"]],
    "openstacks-sat08-adl": [["stacks-avail"]],
    "assembly": [["committed"]],
    "pipesworld-notankage": [["on"]],
}
# Further real domains with acting agents (the scratch folders of
# docs/bench/conformance_extra*.txt; docs/bench/deal_ipc_extra.json). trucks-strips is
# grounded: its truck's state is 0-ary facts named after it (where it is, which of its
# areas is free, which package is in which area).
TRUCK = ["at_truck1_l1", "at_truck1_l2", "at_truck1_l3", "free_a1_truck1", "free_a2_truck1"]
TRUCK += [f"in_package{k}_truck1_a{a}" for k in range(1, 5) for a in (1, 2)]
CASES.update({
    # the robot's base, gripper and cart grasp (base-obstacle also marks carts: shared)
    "tidybot-opt11-strips": [
        ["parked", "base-pos", "gripper-rel", "gripper-empty", "holding", "pushing",
         "not-pushing"],
    ],
    # each robot's place, battery and stop (guarded and config-fullfilled are the team's)
    "recharging-robots-sat23-adl": [["at", "battery", "stopped"]],
    # a robot's cell and motion; free marks cells (shared); nothing-is-moving is 0-ary, global
    "ricochet-robots-opt23-adl": [["at", "is-moving"]],
    "trucks-strips": [TRUCK],
    # the briefcase's place and contents; the second row gives each agent its own copy of
    # where the portables are (at), as depot's second row; is-at is also a goal
    "briefcaseworld": [["is-at", "in"], ["is-at", "in", "at"]],
    # a hiker's place; the second row adds the couple's walked (a pair's own progress)
    "hiking-sequential-multi-core": [["at_person"], ["at_person", "walked"]],
    # no acting object: the crew's day (today) is the one state its action reads: a probe
    # with a conditional effect under forall
    "maintenance-opt14-adl": [["today"]],
    # a car's place: on a curb or behind a car (car-clear and curb-clear are set by others)
    "parking-ipc11-learning-target": [["at-curb", "at-curb-num", "behind-car"]],
    # a server's memory: its usage; the second row adds what it caches
    "data-network": [["usage"], ["usage", "cached"]],
    # a vehicle's load; the second row adds at, which also places packages (driverlog's)
    "logistics": [["in"], ["at", "in"]],
    # the snake's body (blocked also marks walls: shared)
    "snake": [["headsnake", "tailsnake", "nextsnake"]],
    # the one-agent choices for ferry, tsp and nurikabe (docs/explanations/pddl.md)
    "ferry": [["at-ferry", "empty-ferry", "on"]],
    "tsp": [["at"]],
    "nurikabe-sat18": [["robot-pos", "moving"]],
    # a saw's board (empty is only the saw's); the other machines keep no state: a probe
    "woodworking": [["in-highspeed-saw", "empty"]],
})  # fmt: skip


# Larger problems of our own for sample domains whose p01 has one object of the agent's
# kind or a plan with no parallelism (as tests/test_plan_deal.py's storage problem): the
# domain file is read from the sample, the problem written beside it in a scratch folder.
def _zenotravel() -> str:
    levels = " ".join(f"(next fl{i} fl{i + 1})" for i in range(6))
    levels += " " + " ".join(f"(flevel fl{i})" for i in range(7))
    people = {"person1": ("city0", "city1"), "person2": ("city0", "city2"),
              "person3": ("city2", "city1"), "person4": ("city1", "city0")}  # fmt: skip
    init = [levels, "(city city0) (city city1) (city city2)"]
    init += ["(aircraft plane1) (at plane1 city0) (fuel-level plane1 fl3)"]
    init += ["(aircraft plane2) (at plane2 city2) (fuel-level plane2 fl3)"]
    init += [f"(person {p}) (at {p} {a})" for p, (a, _) in people.items()]
    goal = " ".join(f"(at {p} {b})" for p, (_, b) in people.items())
    objects = "plane1 plane2 city0 city1 city2 " + " ".join(people)
    objects += " " + " ".join(f"fl{i}" for i in range(7))
    return (f"(define (problem zeno-own) (:domain zeno-travel) (:objects {objects}) "
            f"(:init {' '.join(init)}) (:goal (and {goal})))")  # fmt: skip


def _satellite() -> str:
    init = ["(satellite s0) (satellite s1) (instrument i0) (instrument i1) (mode m0)"]
    init += ["(on_board i0 s0) (on_board i1 s1) (supports i0 m0) (supports i1 m0)"]
    init += ["(power_avail s0) (power_avail s1) (pointing s0 d0) (pointing s1 d0)"]
    init += ["(calibration_target i0 d1) (calibration_target i1 d1)"]
    init += [f"(direction d{k})" for k in range(6)]
    goal = " ".join(f"(have_image d{k} m0)" for k in range(2, 6))
    objects = "s0 s1 i0 i1 m0 " + " ".join(f"d{k}" for k in range(6))
    return (f"(define (problem sat-own) (:domain satellite) (:objects {objects}) "
            f"(:init {' '.join(init)}) (:goal (and {goal})))")  # fmt: skip


def _driverlog() -> str:
    sites = [f"s{k}" for k in range(4)]
    init = [f"(location {s})" for s in sites]
    for a, b in [(0, 1), (1, 2), (2, 3), (3, 0)]:
        init += [f"(link s{a} s{b}) (link s{b} s{a}) (location p{a}{b})",
                 f"(path s{a} p{a}{b}) (path p{a}{b} s{a}) (path s{b} p{a}{b}) (path p{a}{b} s{b})"]  # fmt: skip
    init += ["(driver d1) (driver d2) (at d1 s0) (at d2 s2)"]
    init += ["(truck t1) (truck t2) (empty t1) (empty t2) (at t1 s0) (at t2 s2)"]
    cargo = {"k1": ("s0", "s1"), "k2": ("s1", "s0"), "k3": ("s2", "s3"), "k4": ("s3", "s2")}
    init += [f"(obj {k}) (at {k} {a})" for k, (a, _) in cargo.items()]
    goal = " ".join(f"(at {k} {b})" for k, (_, b) in cargo.items())
    objects = " ".join([*sites, "p01 p12 p23 p30 d1 d2 t1 t2", *cargo])
    return (f"(define (problem dl-own) (:domain driverlog) (:objects {objects}) "
            f"(:init {' '.join(init)}) (:goal (and {goal})))")  # fmt: skip


def _depot() -> str:
    places = ["depot0", "distributor0", "distributor1"]
    init = ["(place depot0) (depot depot0) (place distributor0) (distributor distributor0)",
            "(place distributor1) (distributor distributor1)"]  # fmt: skip
    for k, place in enumerate(places):
        init += [f"(pallet pallet{k}) (surface pallet{k}) (at pallet{k} {place})",
                 f"(hoist hoist{k}) (locatable hoist{k}) (at hoist{k} {place}) (available hoist{k})"]  # fmt: skip
    init += ["(truck truck0) (locatable truck0) (at truck0 depot0)",
             "(truck truck1) (locatable truck1) (at truck1 distributor1)"]  # fmt: skip
    # two stacks of two crates: crate0 on crate1 on pallet0, crate2 on crate3 on pallet2
    stacks = {"crate1": "pallet0", "crate0": "crate1", "crate3": "pallet2", "crate2": "crate3"}
    where = {"crate0": "depot0", "crate1": "depot0", "crate2": "distributor1",
             "crate3": "distributor1"}  # fmt: skip
    for crate, below in stacks.items():
        init += [f"(crate {crate}) (surface {crate}) (locatable {crate})",
                 f"(at {crate} {where[crate]}) (on {crate} {below})"]  # fmt: skip
    init += ["(clear crate0) (clear crate2) (clear pallet1)"]
    goal = "(on crate1 pallet1) (on crate3 crate1) (on crate0 pallet2) (on crate2 pallet0)"
    objects = " ".join([*places, "truck0 truck1 pallet0 pallet1 pallet2", *stacks,
                        "hoist0 hoist1 hoist2"])  # fmt: skip
    return (f"(define (problem depot-own) (:domain Depot) (:objects {objects}) "
            f"(:init {' '.join(init)}) (:goal (and {goal})))")  # fmt: skip


def _rovers() -> str:
    points = [f"waypoint{k}" for k in range(4)]
    init = [f"(visible {a} {b})" for a in points for b in points if a != b]
    init += [f"(visible_from objective{o} {w})" for o in (0, 1) for w in points]
    init += [f"(at_soil_sample {w})" for w in points] + [f"(at_rock_sample {w})" for w in points]
    init += ["(at_lander general waypoint0) (channel_free general)"]
    for r, start in ((0, 3), (1, 1)):
        init += [f"(at rover{r} waypoint{start}) (available rover{r})",
                 f"(store_of rover{r}store rover{r}) (empty rover{r}store)",
                 f"(equipped_for_soil_analysis rover{r}) (equipped_for_rock_analysis rover{r})",
                 f"(equipped_for_imaging rover{r}) (on_board camera{r} rover{r})",
                 f"(calibration_target camera{r} objective1) (supports camera{r} high_res)"]  # fmt: skip
        for a, b in ((3, 0), (3, 1), (1, 2), (0, 1)):
            init += [f"(can_traverse rover{r} waypoint{a} waypoint{b})",
                     f"(can_traverse rover{r} waypoint{b} waypoint{a})"]  # fmt: skip
    goal = [f"(communicated_soil_data waypoint{w})" for w in (0, 2, 3)]
    goal += [f"(communicated_rock_data waypoint{w})" for w in (1, 3)]
    goal += ["(communicated_image_data objective0 high_res)"]
    objects = ("general - Lander colour high_res low_res - Mode rover0 rover1 - Rover "
               "rover0store rover1store - Store camera0 camera1 - Camera "
               "objective0 objective1 - Objective " + " ".join(points) + " - Waypoint")  # fmt: skip
    return (f"(define (problem rovers-own) (:domain Rover) (:objects {objects}) "
            f"(:init {' '.join(init)}) (:goal (and {' '.join(goal)})))")  # fmt: skip


OWN = {"zenotravel": _zenotravel, "satellite": _satellite, "driverlog": _driverlog,
       "depot": _depot, "rovers": _rovers}  # fmt: skip


def problem_files(folder: Path) -> list[Path]:
    """Every problem file of a domain folder: the ``.pddl`` files but its domain file."""
    return sorted(p for p in folder.glob("*.pddl") if p.name != "domain.pddl")


def tasks_of(
    domain: str, sample: Path, scratch: Path, own: bool, every: bool = False
) -> list[tuple[str, BenchmarkTask]]:
    """The sample's p01 of ``domain`` (``every``: each problem file of its folder, whatever
    its name, read beside the folder's domain file), and our own problem for it (:data:`OWN`)."""
    if every:
        tasks = []
        folder = scratch / "every" / domain
        folder.mkdir(parents=True, exist_ok=True)
        shutil.copy(sample / domain / "domain.pddl", folder / "domain.pddl")
        for number, problem in enumerate(problem_files(sample / domain), 1):
            shutil.copy(problem, folder / f"p{number:02d}.pddl")
            tasks.append((problem.stem, load_task(domain, number, scratch / "every")))
    else:
        tasks = [("p01", load_task(domain, 1, sample))]
    if own and domain in OWN:
        folder = scratch / domain
        folder.mkdir(parents=True, exist_ok=True)
        shutil.copy(sample / domain / "domain.pddl", folder / "domain.pddl")
        (folder / "p01.pddl").write_text(OWN[domain]())
        tasks.append(("own", load_task(domain, 1, scratch)))
    return tasks


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sample", type=Path, default=SAMPLE)
    parser.add_argument(
        "--domains", nargs="*", help="default: the domains of CASES that --sample has"
    )
    parser.add_argument(
        "--agents-file",
        type=Path,
        default=SAMPLE / "agents.yaml",
        help="agent predicates of further domains (the sample's agents.yaml)",
    )
    parser.add_argument("--agents", type=int, nargs="*", default=[2, 3])
    parser.add_argument("--time-limit", type=float, default=30.0, help="SA planner seconds")
    parser.add_argument("--deal-limit", type=int, default=60, help="seconds per plan-deal run")
    parser.add_argument("--no-own", action="store_true", help="the sample's p01 files only")
    parser.add_argument(
        "--every-problem",
        action="store_true",
        help="every problem file of each domain folder (any name), not only p01",
    )
    parser.add_argument("--json", type=Path, help="also write what it prints as a record here")
    args = parser.parse_args(argv)
    with record.capture(args.json, title="plan-deal on real IPC domains"):
        return _run(args, argv)


def _run(args: argparse.Namespace, argv: Sequence[str] | None) -> int:
    planner = PlannerSettings("lama-first", args.time_limit)
    if args.domains is None:
        args.domains = [d for d in CASES if (args.sample / d).is_dir()]
    if args.agents_file.is_file():
        given = read_yaml_file(args.agents_file) or {}
        CASES.update({domain: [list(map(str, preds))] for domain, preds in given.items()})
    shown = " ".join(a for a in (argv if argv is not None else sys.argv[1:]))
    print(f".venv/bin/python bench/bench_deal_ipc.py {shown}".rstrip())
    which = "every problem" if args.every_problem else "p01"
    own = "" if args.no_own else " and our own problems (own)"
    print(f"sample: {args.sample.name}, {which} of each domain{own}; "
          f"SA lama-first {args.time_limit:g} s")  # fmt: skip
    header = ("domain", "task", "agent predicates", "N", "SA", "deal", "fallback", "check_run",
              "independent validator", "deal CPU s")  # fmt: skip
    print(" | ".join(header))
    began = time.perf_counter()
    lines = []
    with tempfile.TemporaryDirectory() as scratch:
        for domain in args.domains:
            tasks = tasks_of(domain, args.sample, Path(scratch), not args.no_own,
                             args.every_problem)  # fmt: skip
            for name, task in tasks:
                for line in rows(domain, name, task, planner, args.agents, args.deal_limit):
                    print(line, flush=True)
                    lines.append(line.split(" | "))
    runs = [c for c in lines if len(c) == len(header)]
    dealt = [c for c in runs if c[6] == "-" and c[5].isdigit() and int(c[5]) < int(c[4])]
    print(f"{len(runs)} runs: {len(dealt)} dealt shorter than SA, "
          f"{sum(c[5] == 'CRASH' for c in runs)} crashed, "
          f"{sum('INVALID' in c[7] or 'INVALID' in c[8] for c in runs)} invalid, "
          f"{sum('unified-planning' not in c[8] for c in runs)} not read by unified-planning; "
          f"total {time.perf_counter() - began:.0f} s")  # fmt: skip
    return 0


def rows(
    domain: str,
    name: str,
    task: BenchmarkTask,
    planner: PlannerSettings,
    agent_counts: Sequence[int],
    deal_limit: int,
) -> Iterator[str]:
    """The table's rows for one task: each agent predicate set and N."""
    try:
        sa = run_single_agent(MethodRequest(task, planner=planner))
    except Exception as error:
        yield f"{domain} | {name} | - | - | SA error: {type(error).__name__}: {error}"[:200]
        return
    if sa.exec_length is None:
        yield f"{domain} | {name} | - | - | no SA plan ({sa.message[:80]})"
        return
    sa_plan = sa.planner_calls[0].result
    validator = IndependentValidator(task.domain_path, task.problem_path)
    for preds in CASES[domain]:
        for agents in agent_counts:
            label = ",".join(preds)
            request = MethodRequest(task, agents, planner, preds, sa_plan=sa_plan)
            start = time.process_time()
            run = deal_within(request, deal_limit, 100)
            if isinstance(run, str):
                spent = time.process_time() - start
                yield (f"{domain} | {name} | {label} | {agents} | {sa.exec_length} | CRASH | "
                       f"{run} | - | - | {spent:.2f}")  # fmt: skip
                continue
            yield " | ".join(str(x) for x in (
                domain, name, label, agents, sa.exec_length, run.exec_length,
                fallback_text(run), our_verdict(task, run, preds),
                independent_verdict(validator, run, preds),
                f"{deal_seconds(run):.2f}",
            ))  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
