"""Conformance: twostep reads, plans and validates real PDDL as Fast Downward does.

Checked by things independent of twostep: Fast Downward itself on the original files, the
independent validator of ``checkers`` (unified-planning's validator, and a
simulator of Fast Downward's grounding written apart from twostep), and the values in
each construct fixture's ``expected.yaml``, derived by hand.

* the validator: hand-written grounded tasks with known answers (axiom layers, negation by
  failure, conditional effects); on every construct fixture it accepts Fast Downward's
  optimal plan and the hand-written valid plans, and rejects every plan with a step
  dropped from an optimal plan (it would beat the optimum) and the hand-written wrong
  plans (swapped steps, a wrong argument); schedules with interfering or missing steps;
* the fixtures: Fast Downward's optimal search on the original files agrees with the
  hand-derived optimum;
* twostep (through its command line, as the conformance bench runs it) on every construct
  fixture and on a handful of IPC sample domains when ``<repo>/../shared/ipc-sample``
  exists: it loads the files, solves, its plan is valid on the original files, and its
  ``sa_length``/``sa_cost`` are the plan's; MA and plan-deal schedules (N = 2) re-validate.

Before issue 17 (twostep reading PDDL as Fast Downward does) seven construct fixtures and
four of the IPC domains here failed (docs/bench/archive/2026-11-24_conformance_before.txt says why); they pass
now, with no test marked as expected to fail.
"""

from __future__ import annotations

import random
import subprocess
import sys
import tempfile
from functools import cache
from pathlib import Path
from typing import Any

import pytest
import yaml

from checkers import IndependentValidator, fast_downward, sas, unified
from checkers.constants import move_constants
from evaluation.conformance import ProblemFiles, find_problems, loaded, reason_of, run_twostep
from tests.support.skips import IPC_SAMPLE, needs_ipc_sample

REPO = Path(__file__).resolve().parent.parent
CONSTRUCTS = Path(__file__).resolve().parent / "fixtures" / "constructs"
TIME_LIMIT_S = 30
RUN_TIMEOUT_S = 300

FIXTURES = sorted(p.name for p in CONSTRUCTS.iterdir() if (p / "expected.yaml").is_file())


def expected(name: str) -> dict[str, Any]:
    return dict(yaml.safe_load((CONSTRUCTS / name / "expected.yaml").read_text()))


@cache
def readable_files(name: str, problem: str = "p01") -> tuple[Path, Path]:
    """The fixture's files as the independent checkers read them: as they are, or with the
    objects only the problem declares moved to the domain's constants."""
    folder = CONSTRUCTS / name
    domain, task = folder / "domain.pddl", folder / f"{problem}.pddl"
    moved = expected(name).get("constants_declared_by_problem")
    if not moved:
        return domain, task
    return move_constants(domain, task, moved, Path(tempfile.mkdtemp(prefix=f"{name}-")))


@cache
def validator(name: str, problem: str = "p01") -> IndependentValidator:
    return IndependentValidator(*readable_files(name, problem))


@cache
def optimal_plan(name: str, problem: str = "p01") -> fast_downward.PlannerRun:
    return fast_downward.plan(*readable_files(name, problem), fast_downward.OPTIMAL_SEARCH, 60)


# ------------------------------------------------------ the simulator on hand-made tasks


def sas_text(variables: list[tuple[int, list[str]]], init: list[int], goal: list[tuple[int, int]],
             operators: list[str], axioms: list[str], metric: int = 0) -> str:  # fmt: skip
    lines = ["begin_version", "3", "end_version", "begin_metric", str(metric), "end_metric"]
    lines.append(str(len(variables)))
    for number, (layer, values) in enumerate(variables):
        lines += [
            "begin_variable",
            f"var{number}",
            str(layer),
            str(len(values)),
            *values,
            "end_variable",
        ]
    lines += ["0", "begin_state", *map(str, init), "end_state", "begin_goal", str(len(goal))]
    lines += [f"{v} {x}" for v, x in goal] + ["end_goal", str(len(operators)), *operators]
    lines += [str(len(axioms)), *axioms]
    return "\n".join(lines) + "\n"


def binary(name: str) -> list[str]:
    return [f"Atom {name}", f"NegatedAtom {name}"]


def test_axioms_by_layers_with_negation_by_failure() -> None:
    # var0 p (state), var1 q (state); var2 r = p or r-via-q (layer 0, recursive through
    # var3 s = r, layer 0); var4 t = not r (layer 1: negation by failure of layer 0).
    variables = [(-1, binary("p()")), (-1, binary("q()")), (0, binary("r()")),
                 (0, binary("s()")), (1, binary("t()"))]  # fmt: skip
    axioms = [
        "begin_rule\n1\n0 0\n2 1 0\nend_rule",  # r <- p
        "begin_rule\n2\n1 0\n3 0\n2 1 0\nend_rule",  # r <- q and s
        "begin_rule\n1\n2 0\n3 1 0\nend_rule",  # s <- r
        "begin_rule\n1\n2 1\n4 1 0\nend_rule",  # t <- not r (r at its default)
    ]
    set_p = "begin_operator\nset-p\n0\n1\n0 0 -1 0\n1\nend_operator"
    clear_p = "begin_operator\nclear-p\n0\n1\n0 0 0 1\n1\nend_operator"
    needs_t = "begin_operator\nneeds-t\n1\n4 0\n1\n0 1 -1 1\n1\nend_operator"
    text = sas_text(variables, [1, 0, 1, 1, 1], [(2, 0)], [set_p, clear_p, needs_t], axioms)
    task = sas.parse_sas(text)
    # Initially q holds but s needs r, which needs p or s: the recursion has no base: r false, t true.
    state = sas.initial_state(task)
    assert (state[2], state[3], state[4]) == (1, 1, 0)
    assert not sas.run_plan(task, []).valid
    assert sas.run_plan(task, ["(needs-t)"]).valid is False  # goal r still false
    after = sas.run_plan(task, ["(needs-t)", "(set-p)"])
    assert after.valid and after.final_state is not None
    assert after.final_state[2:] == (0, 0, 1)  # r, s derived; t no longer
    # With p set, t is false, so needs-t no longer applies.
    check = sas.run_plan(task, ["(set-p)", "(needs-t)"])
    assert not check.valid and "t()" in check.reason
    # Clearing p again: r was derived through s and q, but s depends on r: recomputed from
    # defaults, the cycle has no support, so r is false again.
    assert not sas.run_plan(task, ["(set-p)", "(clear-p)"]).valid


def test_conditional_effects_read_the_state_before_the_step() -> None:
    # Swap: if a then (not a, b); if b then (not b, a). Applying it once from a: b only.
    variables = [(-1, binary("a()")), (-1, binary("b()"))]
    effects = ["1 0 0 0 -1 1", "1 0 0 1 -1 0", "1 1 0 1 -1 1", "1 1 0 0 -1 0"]
    swap = "begin_operator\nswap\n0\n4\n" + "\n".join(effects) + "\n3\nend_operator"
    task = sas.parse_sas(sas_text(variables, [0, 1], [(1, 0), (0, 1)], [swap], [], metric=1))
    result = sas.run_plan(task, ["(swap)"])
    assert result.valid and result.cost == 3
    assert not sas.run_plan(task, ["(swap)", "(swap)"]).valid  # back to a, not b
    assert not sas.run_plan(task, ["(unknown)"]).valid


# ----------------------------------------------------------- fixtures: the hand-derived values


@pytest.mark.parametrize("name", FIXTURES)
def test_fast_downward_confirms_the_hand_derived_optimum(name: str) -> None:
    wanted = expected(name)["p01"]
    run = optimal_plan(name)
    assert run.status == "solved" and run.plan is not None, run.message
    if "optimal_cost" in wanted:
        assert run.cost == wanted["optimal_cost"]
    length = wanted.get("optimal_length", wanted.get("optimal_cost_length"))
    assert len(run.plan) == length
    if "constants_declared_by_problem" in expected(name):  # as written, Fast Downward refuses
        folder = CONSTRUCTS / name
        original = fast_downward.plan(folder / "domain.pddl", folder / "p01.pddl")
        assert original.status == "error" and "Undefined object" in original.message


@pytest.mark.parametrize("name", FIXTURES)
def test_validator_accepts_the_plans_and_rejects_the_wrong_ones(name: str) -> None:
    wanted = expected(name)["p01"]
    check = validator(name)
    best = optimal_plan(name).plan
    assert best is not None
    verdict = check.check_plan(best)
    assert verdict.valid, verdict.reason
    assert verdict.cost == optimal_plan(name).cost
    for number, plan in enumerate(wanted["valid_plans"]):
        verdict = check.check_plan(plan)
        assert verdict.valid, (plan, verdict.reason)
        if "costs" in wanted:
            assert verdict.cost == wanted["costs"][number]
    for case in wanted["invalid_plans"]:
        assert not check.check_plan(case["plan"]).valid, case["why"]
    # A plan shorter (cheaper) than the optimum cannot be valid: drop each step in turn.
    for index in range(len(best)):
        shorter = best[:index] + best[index + 1 :]
        assert not check.check_plan(shorter).valid, f"step {index + 1} dropped"


def test_validator_uses_both_checkers_where_unified_planning_reads_the_files() -> None:
    assert validator("imply").up_problem is not None
    assert validator("imply").translation is not None
    for name in (
        "derived_predicates",
        "either_types",
        "repeated_parameter_name",
        "variable_glued_to_name",
    ):
        assert validator(name).up_problem is None  # the simulator alone checks these
        assert validator(name).translation is not None
    untouched = IndependentValidator(CONSTRUCTS / "problem_constants" / "domain.pddl",
                                     CONSTRUCTS / "problem_constants" / "p01.pddl")  # fmt: skip
    verdict = untouched.check_plan(expected("problem_constants")["p01"]["valid_plans"][0])
    assert not verdict.valid and "no independent checker" in verdict.reason


# ------------------------------------------------------------------ schedules (N = 2)

PORTERS_SCHEDULE = [
    [["agent0", "(walk porter hall left)"], ["agent1", "(walk porter hall right)"]],
    [["agent0", "(pick porter b1 left)"], ["agent1", "(pick porter b2 right)"]],
    [["agent0", "(walk porter left hall)"], ["agent1", "(walk porter right hall)"]],
    [["agent0", "(walk porter hall right)"], ["agent1", "(walk porter hall left)"]],
    [["agent0", "(drop porter b1 right)"], ["agent1", "(drop porter b2 left)"]],
]


def plans_of(schedule: list[list[list[str]]]) -> dict[str, list[str]]:
    plans: dict[str, list[str]] = {"agent0": [], "agent1": []}
    for step in schedule:
        for agent, action in step:
            plans[agent].append(action)
    return plans


def test_schedule_checker() -> None:
    check = validator("agent_type")
    preds = expected("agent_type")["agent_predicates"]
    order = ["agent0", "agent1"]
    good = check.check_schedule(order, plans_of(PORTERS_SCHEDULE), PORTERS_SCHEDULE, preds)
    assert good.valid, good.reason
    assert "unified-planning" in good.checkers and "simulator" in good.checkers
    # Without per-agent copies of the agent facts, one porter could not be in two rooms.
    assert not check.check_schedule(order, plans_of(PORTERS_SCHEDULE), PORTERS_SCHEDULE, []).valid
    # Both agents take the same box in one step: only one order runs.
    clash = [[["agent0", "(walk porter hall left)"], ["agent1", "(walk porter hall left)"]],
             [["agent0", "(pick porter b1 left)"], ["agent1", "(pick porter b1 left)"]]]  # fmt: skip
    verdict = check.check_schedule(order, plans_of(clash), clash, preds)
    assert not verdict.valid
    # A step of agent0's plan is missing from the schedule.
    plans = plans_of(PORTERS_SCHEDULE)
    plans["agent0"].append("(walk porter right hall)")
    assert "plan" in check.check_schedule(order, plans, PORTERS_SCHEDULE, preds).reason
    # Swapped time steps: agent1 drops a box before it reaches the room.
    swapped = [PORTERS_SCHEDULE[0], PORTERS_SCHEDULE[1], PORTERS_SCHEDULE[4], PORTERS_SCHEDULE[3],
               PORTERS_SCHEDULE[2]]  # fmt: skip
    assert not check.check_schedule(order, plans_of(swapped), swapped, preds).valid
    # The goal is not reached when agent1 stops early.
    short = [[pair for pair in step if pair[0] == "agent0"] for step in PORTERS_SCHEDULE]
    assert not check.check_schedule(order, plans_of(short), short, preds).valid


def test_a_step_whose_actions_interfere_is_rejected_by_the_simulator() -> None:
    # The keys are shared (no agent predicates): agent1 unlocks in the step in which
    # agent0 takes the key the lock needs, which works in one order only.
    check = validator("disjunctive_preconditions")
    step = [["agent0", "(take k19)"], ["agent1", "(unlock d1)"]]
    verdict = check.check_schedule(["agent0", "agent1"], plans_of([step]), [step], [])
    assert not verdict.valid and "step 1 in the order" in verdict.reason
    fine = [[["agent0", "(take k19)"]], [["agent1", "(unlock d1)"]]]
    assert check.check_schedule(["agent0", "agent1"], plans_of(fine), fine, []).valid


# ------------------------------------------------------------- twostep on the fixtures


def twostep_sa(files: ProblemFiles) -> tuple[Any, list[str]]:
    run = run_twostep(files, ["method=sa"], TIME_LIMIT_S, RUN_TIMEOUT_S)
    assert loaded(run), reason_of(run)
    result = run.result or {}
    assert result.get("success"), reason_of(run)
    return result, list(result["plans"][result["agent_order"][0]])


def fixture_files(name: str, problem: str = "p01") -> ProblemFiles:
    folder = CONSTRUCTS / name
    return ProblemFiles(name, folder / "domain.pddl", folder / f"{problem}.pddl", None)


@pytest.mark.parametrize("name", FIXTURES)
def test_twostep_single_agent_on_construct(name: str) -> None:
    wanted = expected(name)["p01"]
    result, plan = twostep_sa(fixture_files(name))
    verdict = validator(name).check_plan(plan)
    assert verdict.valid, verdict.reason
    assert result["sa_length"] == len(plan)  # only the task's own actions are counted
    assert result["sa_cost"] == verdict.cost
    assert len(plan) >= wanted.get("optimal_length", wanted.get("shortest_length", 0))
    assert verdict.cost is not None and verdict.cost >= wanted.get("optimal_cost", 0)


# Fixtures with agent predicates; one in the fast suite, the rest with -m slow.
MULTI_AGENT_FIXTURES = [
    name if name == "agent_type" else pytest.param(name, marks=pytest.mark.slow)
    for name in FIXTURES
    if expected(name)["agent_predicates"]
]


@pytest.mark.parametrize("name", MULTI_AGENT_FIXTURES)
@pytest.mark.parametrize("method", [["method=ma"], ["method=twostep", "decomposer=plan-deal"]])
def test_twostep_schedules_on_construct(name: str, method: list[str]) -> None:
    preds = expected(name)["agent_predicates"]
    overrides = [*method, "agents=2", f"domain.agent_predicates=[{','.join(preds)}]"]
    run = run_twostep(fixture_files(name), overrides, TIME_LIMIT_S, RUN_TIMEOUT_S)
    result = run.result or {}
    assert result.get("success"), reason_of(run)
    verdict = validator(name).check_schedule(
        result["agent_order"], result["plans"], result["schedule"], preds
    )
    assert verdict.valid, verdict.reason
    assert result["exec_length"] == len(result["schedule"])


# ------------------------------------------------------------ the IPC sample, when present


# A handful covering the constructs: conditional effects (airport-adl), costs from
# functions (elevators), axioms (psr), a variable glued to a name (zenotravel), and plain
# STRIPS with MA and plan-deal (blocks).
SAMPLE_SUBSET = ("airport-adl", "elevators-sat08-strips", "psr-middle", "zenotravel", "blocks")


def sample_files(domain: str) -> ProblemFiles:
    (files,) = [p for p in find_problems(IPC_SAMPLE) if p.domain_name == domain]
    return files


@needs_ipc_sample
@pytest.mark.parametrize("domain", SAMPLE_SUBSET)
def test_twostep_single_agent_on_ipc_sample(domain: str) -> None:
    files = sample_files(domain)
    check = IndependentValidator(files.domain, files.problem)
    reference = fast_downward.plan(files.domain, files.problem, time_limit_s=TIME_LIMIT_S)
    assert reference.plan is not None and check.check_plan(reference.plan).valid
    result, plan = twostep_sa(files)
    verdict = check.check_plan(plan)
    assert verdict.valid, verdict.reason
    assert result["sa_length"] == len(plan) and result["sa_cost"] == verdict.cost


@needs_ipc_sample
def test_twostep_schedules_on_ipc_sample() -> None:
    agents = yaml.safe_load((IPC_SAMPLE / "agents.yaml").read_text())
    files = sample_files("blocks")
    check = IndependentValidator(files.domain, files.problem)
    for method in (["method=ma"], ["method=twostep", "decomposer=plan-deal"]):
        preds = agents["blocks"]
        overrides = [*method, "agents=2", f"domain.agent_predicates=[{','.join(preds)}]"]
        run = run_twostep(files, overrides, TIME_LIMIT_S, RUN_TIMEOUT_S)
        result = run.result or {}
        assert result.get("success"), reason_of(run)
        verdict = check.check_schedule(
            result["agent_order"], result["plans"], result["schedule"], preds
        )
        assert verdict.valid, (method, verdict.reason)


@needs_ipc_sample
@pytest.mark.slow
@pytest.mark.timeout(3600)
def test_simulator_agrees_with_unified_planning_on_mutated_plans() -> None:
    """On every sample domain unified-planning reads: Fast Downward's plan and 30 random
    mutants (a step dropped, two neighbours swapped, an argument replaced) get the same
    verdict from both checkers."""
    rng = random.Random(0)
    compared = 0
    for files in find_problems(IPC_SAMPLE):
        check = IndependentValidator(files.domain, files.problem)
        if check.up_problem is None or check.translation is None:
            continue
        run = fast_downward.plan(files.domain, files.problem, time_limit_s=TIME_LIMIT_S)
        if run.plan is None:
            continue
        names = sorted({a for step in run.plan for a in sas.step_name(step).split()[1:]})
        for _ in range(30):
            plan = list(run.plan)
            where = rng.randrange(len(plan))
            kind = rng.randrange(3)
            if kind == 0:
                del plan[where]
            elif kind == 1 and len(plan) > 1:
                where = min(where, len(plan) - 2)
                plan[where], plan[where + 1] = plan[where + 1], plan[where]
            else:
                parts = sas.step_name(plan[where]).split()
                if len(parts) > 1:
                    parts[rng.randrange(1, len(parts))] = rng.choice(names)
                plan[where] = "(" + " ".join(parts) + ")"
            simulated = sas.run_plan(check.translation.task, plan)
            by_up = unified.validate_plan(check.up_problem, plan)
            assert simulated.valid == by_up.valid, (files.key, plan, simulated.reason, by_up.reason)
            compared += 1
    assert compared >= 300


# ------------------------------------------------------------------- the bench itself


def _bench_conformance(argv: list[str]) -> subprocess.CompletedProcess[str]:
    """``bench/bench_conformance.py`` run as its docs show it (its exit code and output)."""
    script = REPO / "bench" / "bench_conformance.py"
    return subprocess.run([sys.executable, str(script), *argv], capture_output=True, text=True,
                          cwd=REPO, timeout=RUN_TIMEOUT_S, check=False)  # fmt: skip


def test_bench_on_a_tree_of_files_and_resume(tmp_path: Path) -> None:
    """Any tree of domain.pddl + problem files works (staged for twostep through links);
    rows go to --out and a second run reuses them."""
    tree = tmp_path / "corpus" / "family" / "porters"
    tree.mkdir(parents=True)
    (tree / "domain.pddl").write_text((CONSTRUCTS / "agent_type" / "domain.pddl").read_text())
    (tree / "swap-boxes.pddl").write_text((CONSTRUCTS / "agent_type" / "p01.pddl").read_text())
    (tree / "notes.pddl").write_text("; not a problem\n(define (domain other))\n")
    (found,) = find_problems(tmp_path / "corpus")
    assert (found.domain_name, found.problem.name, found.task) == (
        "family/porters",
        "swap-boxes.pddl",
        None,
    )
    agents = tmp_path / "agents.yaml"
    agents.write_text("family/porters: [at, carrying, free]\n")
    out = tmp_path / "rows.json"
    argv = ["--corpus", str(tmp_path / "corpus"), "--agents", str(agents), "--out", str(out)]
    first = _bench_conformance(argv)
    assert first.returncode == 0, first.stderr
    printed = first.stdout
    assert "| family/porters | swap-boxes.pddl | yes |" in printed
    assert "SA solved+valid 1/1 of the problems FD solves" in printed
    assert "MA valid 1/1, plan-deal valid 1/1" in printed
    again = _bench_conformance(argv)
    assert again.returncode == 0, again.stderr
    assert "1 already in" in again.stdout
