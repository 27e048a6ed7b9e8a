"""Tests of the benchmark generators, the describers and the ``twostep-data`` command."""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

import pytest
import yaml

from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from twostep.cli.data import build_parser, compare_files, main
from twostep.generators import (
    DOMAINS,
    GENERATORS,
    as_problem,
    benchmark_files,
    benchmark_task,
    domain_model,
    example_task,
    scale_files,
    scaled_task,
    static_file,
)
from twostep.generators.describe import DESCRIBERS, describe_generic, describe_problem
from twostep.generators.sizes import BENCHMARK_SIZES
from twostep.generators.spec import TaskSpec
from twostep.pddl import Domain, load_problem, parse_goal, parse_problem
from twostep.plans.simulate import Grounder, read_plan, simulate

EXPERT_DOMAINS = ("blocksworld", "grippers", "termes", "tyreworld")
EXPERT_TASKS = ["p01", "p06", "p11", "p16"]


@pytest.fixture(scope="module")
def models() -> dict[str, Domain]:
    return {domain: domain_model(domain) for domain in DOMAINS}


def type_counts(task: TaskSpec) -> dict[str, int]:
    """Objects per type, the domain's constants (tyreworld's tools) included."""
    objects = dict(task.objects) | domain_model(task.domain).constants
    return dict(Counter(objects.values()))


def words(text: str) -> set[str]:
    return set(re.findall(r"[a-z0-9-]+", text))


# ------------------------------------------------------------------ generated data


def test_generate_is_byte_identical_to_committed_data(data_root: Path) -> None:
    for domain in DOMAINS:
        files = benchmark_files(domain)
        assert len(files) == 2 + 2 * 21 + 1  # domain.*, p01..p20 and p_example, example plan
        for name, text in files.items():
            assert (data_root / domain / name).read_text() == text, f"{domain}/{name}"


def test_every_task_has_the_sizes_of_the_table() -> None:
    for domain in DOMAINS:
        sizes = BENCHMARK_SIZES[domain]
        assert len(sizes) == 20
        for index, size in enumerate(sizes, start=1):
            task = benchmark_task(domain, index)
            assert type_counts(task) == dict(size.objects), f"{domain} p{index:02d}"
            assert len(task.goal) + len(task.negative_goal) == size.goal_atoms


def test_barman_has_three_shakers_everywhere() -> None:
    tasks = [benchmark_task("barman", i) for i in range(1, 21)] + [example_task("barman")]
    for task in tasks:
        assert type_counts(task)["shaker"] == 3


def test_sizes_of_some_table_rows() -> None:
    # spot checks against ../shared/benchmark-sizes.md, in case the table itself drifts
    assert dict(BENCHMARK_SIZES["grippers"][15].objects) == {
        "gripper": 8, "object": 8, "robot": 4, "room": 4,
    }  # fmt: skip
    assert BENCHMARK_SIZES["tyreworld"][1].count("hub") == 9
    assert BENCHMARK_SIZES["tyreworld"][19].goal_atoms == 84
    assert [s.count("position") for s in BENCHMARK_SIZES["termes"]][5:11] == [
        12,
        20,
        20,
        20,
        20,
        12,
    ]
    assert BENCHMARK_SIZES["barman"][12].count("shot") == 8


def test_parsed_pddl_equals_the_spec(models: dict[str, Domain]) -> None:
    """The fast path (spec -> Problem) and the PDDL text parsed by unified-planning agree."""
    for domain in DOMAINS:
        for task in (example_task(domain), benchmark_task(domain, 7)):
            parsed = parse_problem(static_file(domain, ".pddl"), task.to_pddl())
            direct = as_problem(task, models[domain])
            assert parsed.objects == direct.objects
            assert parsed.init == direct.init
            assert parsed.goal == direct.goal


def test_goals_do_not_hold_at_the_start() -> None:
    for domain in DOMAINS:
        for index in range(1, 21):
            task = benchmark_task(domain, index)
            assert not set(task.goal) <= set(task.init), f"{domain} p{index:02d}"


def test_names_are_lowercase_and_files_end_with_newline() -> None:
    for domain in DOMAINS:
        for name, text in benchmark_files(domain).items():
            assert text.endswith("\n")
            if name.endswith(".pddl") and name != "domain.pddl":
                assert text == text.lower(), name


def test_each_task_has_its_own_rng() -> None:
    alone = benchmark_task("blocksworld", 12, seed=0)
    assert alone.to_pddl() == benchmark_files("blocksworld")["p12.pddl"]
    assert benchmark_task("blocksworld", 12, seed=1).to_pddl() != alone.to_pddl()
    assert benchmark_task("grippers", 16, seed=3) == benchmark_task("grippers", 16, seed=3)


def test_termes_goal_is_towers_off_the_depot_and_no_held_block() -> None:
    for index in range(1, 21):
        task = benchmark_task("termes", index)
        assert task.negative_goal == (("has-block",),)
        tall = [f for f in task.goal if f[2] != "n0"]
        numbers = [name for name, type_name in task.objects if type_name == "numb"]
        assert max(int(f[2][1:]) for f in tall) == len(numbers) - 1  # the tallest uses all
        assert 1 <= len(tall) <= 6 and min(int(f[2][1:]) for f in tall) >= 2
        (depot,) = [f[1] for f in task.init if f[0] == "is-depot"]
        assert ("at", depot) in task.init and depot not in {f[1] for f in tall}


def test_example_plans_reach_their_goal(models: dict[str, Domain]) -> None:
    for domain in DOMAINS:
        problem = as_problem(example_task(domain), models[domain])
        plan = read_plan(static_file(domain, ".example.sol"))
        assert plan, domain
        end = simulate(problem.init, Grounder(problem).ground_plan(plan))
        assert problem.goal.holds(end), domain


# ------------------------------------------------------------------ expert subgoals


@pytest.mark.parametrize("domain", EXPERT_DOMAINS)
def test_expert_subgoals_are_well_formed(
    data_root: Path, models: dict[str, Domain], domain: str
) -> None:
    experts = yaml.safe_load((data_root / domain / "expert.yaml").read_text())
    assert sorted(experts) == EXPERT_TASKS
    for task, by_agents in experts.items():
        problem = as_problem(benchmark_task(domain, int(task[1:])), models[domain])
        assert list(by_agents) == [2]
        (text,) = by_agents[2]
        goal = parse_goal(text, problem)  # known predicates and objects
        assert not goal.holds(problem.init), f"{domain} {task}: already true"


@pytest.mark.slow
@pytest.mark.parametrize("domain", EXPERT_DOMAINS)
def test_expert_subgoals_are_solvable(data_root: Path, domain: str) -> None:
    from twostep.planner import PlannerSettings, plan

    experts = yaml.safe_load((data_root / domain / "expert.yaml").read_text())
    for task, by_agents in experts.items():
        problem = load_problem(
            data_root / domain / "domain.pddl", data_root / domain / f"{task}.pddl"
        )
        for text in by_agents[2]:
            result = plan(problem.with_state(goal=parse_goal(text, problem)), PlannerSettings())
            assert result.solved, f"{domain} {task}: {result.message}"


# ------------------------------------------------------------------ describers


def test_describers_name_every_goal_object(models: dict[str, Domain]) -> None:
    for domain in DOMAINS:
        for task in (example_task(domain), benchmark_task(domain, 1), benchmark_task(domain, 16)):
            problem = as_problem(task, models[domain])
            text = describe_problem(problem)
            assert text == DESCRIBERS[domain](problem)
            said = words(text)
            for fact in problem.goal.positive:
                assert set(fact[1:]) <= said, (domain, fact)


def test_describers_say_states_the_generator_never_makes(models: dict[str, Domain]) -> None:
    blocks = as_problem(benchmark_task("blocksworld", 6), models["blocksworld"])
    held = (blocks.init - {("arm-empty",), ("on", "b4", "b1"), ("clear", "b4")}) | {
        ("holding", "b4"), ("clear", "b1"),
    }  # fmt: skip
    assert "You are holding b4." in describe_problem(blocks.with_state(init=held))
    termes = as_problem(benchmark_task("termes", 3), models["termes"])
    carrying = describe_problem(termes.with_state(init=termes.init | {("has-block",)}))
    assert "The robot is carrying a block." in carrying
    assert "The robot is not carrying a block." not in carrying


def test_blocksworld_description_reads_like_the_paper(models: dict[str, Domain]) -> None:
    text = describe_problem(as_problem(benchmark_task("blocksworld", 6), models["blocksworld"]))
    assert text.startswith("You have 5 blocks: b1, b2, b3, b4 and b5.\n")
    assert "b1 is on top of b3." in text
    assert "Your arm is empty." in text
    assert "b4 should be on top of b3." in text


def test_generic_describer_on_an_unknown_domain() -> None:
    problem = parse_problem(
        BLOCKS_DOMAIN,
        blocks_problem(
            "(on-table a) (on b a) (clear b) (arm-empty)", "(on a b) (not (on b a))", "a b"
        ),
    )
    assert problem.domain.name not in DESCRIBERS
    text = describe_problem(problem)
    assert text == describe_generic(problem)
    assert "There are 2 objects: a and b." in text
    assert "on(b, a) is true." in text
    assert "arm-empty is true." in text
    goal = text.split("Your goal")[1]
    assert "on(a, b) is true." in goal and "on(b, a) is false." in goal


def test_domain_override_picks_a_describer(models: dict[str, Domain]) -> None:
    problem = as_problem(benchmark_task("grippers", 2), models["grippers"])
    assert describe_problem(problem, "no-such-domain") == describe_generic(problem)


# ------------------------------------------------------------------ command line


def test_cli_generate_then_check(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["generate", "--out", str(tmp_path), "--domain", "grippers"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["grippers"]
    assert main(["check", "--data", str(tmp_path), "--domain", "grippers"]) == 0
    (tmp_path / "grippers" / "p03.nl").write_text("edited\n")
    (tmp_path / "grippers" / "p04.pddl").unlink()
    capsys.readouterr()
    assert main(["check", "--data", str(tmp_path), "--domain", "grippers"]) == 1
    err = capsys.readouterr().err
    assert "2 file(s) do not match" in err
    assert "p03.nl:1: expected" in err and "found 'edited'" in err
    assert "p04.pddl: missing" in err


def test_cli_scale(tmp_path: Path) -> None:
    out = tmp_path / "grippers-12"
    assert (
        main(["scale", "--domain", "grippers", "--size", "12", "--out", str(out), "--count", "2"])
        == 0
    )
    names = {p.name for p in out.iterdir()}
    assert {"domain.pddl", "domain.nl", "p01.pddl", "p02.nl", "p_example.sol"} <= names
    problem = load_problem(out / "domain.pddl", out / "p02.pddl")
    assert Counter(problem.objects.values())["object"] == 12
    assert main(["scale", "--domain", "grippers", "--size", "0", "--out", str(out)]) == 2


def test_stress_tasks_are_what_their_readme_commands_write(data_root: Path) -> None:
    readme = (data_root / "stress" / "README.md").read_text()
    commands = re.findall(r"twostep-data (scale .+)", readme)
    assert len(commands) == 4
    for command in commands:
        args = build_parser().parse_args(command.split())
        folder = Path(args.out)
        assert folder.parts[:2] == ("data", "stress")
        files = scale_files(args.domain, args.size, args.count, args.seed)
        assert compare_files(data_root.parent / folder, files) == []
        assert sorted(p.name for p in (data_root.parent / folder).iterdir()) == sorted(files)


def test_scaled_tasks_have_the_requested_size() -> None:
    assert type_counts(scaled_task("blocksworld", 30))["block"] == 30
    assert type_counts(scaled_task("tyreworld", 40))["hub"] == 40
    assert type_counts(scaled_task("grippers", 40))["object"] == 40
    assert type_counts(scaled_task("barman", 12))["cocktail"] == 12
    assert type_counts(scaled_task("termes", 6))["position"] == 30  # 5 x 6
    assert sum(f[2] == "n3" for f in scaled_task("termes", 6).goal) == 6  # towers
    assert scaled_task("blocksworld", 30, 1) != scaled_task("blocksworld", 30, 2)
    for generator in GENERATORS.values():
        assert generator.scale_unit


# ------------------------------------------------------------------ planning (slow)


@pytest.mark.slow
@pytest.mark.parametrize("domain", DOMAINS)
def test_every_task_solves_with_lama_first(data_root: Path, domain: str) -> None:
    from twostep.planner import PlannerSettings, plan, returncodes

    for index in range(1, 21):
        folder = data_root / domain
        problem = load_problem(folder / "domain.pddl", folder / f"p{index:02d}.pddl")
        result = plan(problem, PlannerSettings("lama-first", search_time_limit_s=60))
        assert result.solved and result.plan is not None, f"{domain} p{index:02d}: {result.message}"
        # The search ended on its own with its plan, within its time limit: not stopped by
        # the limit (a plan found "out of time" is solved too) nor by the wall-clock guard.
        assert result.exit_code == returncodes.SUCCESS and not result.guard_stopped, (
            f"{domain} p{index:02d}: exit {result.exit_code}: {result.message}"
        )
        end = simulate(problem.init, Grounder(problem).ground_plan(result.plan))
        assert problem.goal.holds(end)
