"""The generator and translator prompts: all parts present, in order, nothing unfilled."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.conftest import REPO
from tests.support.data import DOMAIN_NL, EXAMPLE_NL, TASK_NL, make_blocksworld_data
from twostep.cli.prompts import main as prompts_main
from twostep.llm.prompts import TEMPLATES, generator_messages, template, translator_messages
from twostep.pddl import load_problem, parse_goal
from twostep.plans.simulate import Grounder, simulate
from twostep.tasks.benchmark import BenchmarkTask, load_task

LEFTOVER = re.compile(r"\$\{?[A-Za-z_]|<condition>\s*$")


@pytest.fixture
def task(tmp_path: Path) -> BenchmarkTask:
    return load_task("blocksworld", 1, make_blocksworld_data(tmp_path))


def _positions(text: str, parts: list[str]) -> list[int]:
    positions = [text.find(p) for p in parts]
    assert all(p >= 0 for p in positions), [
        p for p, i in zip(parts, positions, strict=True) if i < 0
    ]
    return positions


def test_templates_exist_and_use_only_known_placeholders() -> None:
    for name in TEMPLATES:
        names = set(re.findall(r"\$(\w+)", template(name).template))
        assert names <= {
            "helper_names",
            "domain_description",
            "example_task",
            "example_plan",
            "task",
            "agents",
            "n_helpers",
            "earlier",
            "helper",
            "problem_pddl",
            "example_goal_nl",
            "example_goal_pddl",
            "subgoal",
        }, name


def test_generator_prompt_has_every_part_in_order(task: BenchmarkTask) -> None:
    earlier = ["b is on the table and the arm is empty"]
    system, user = generator_messages(task, agents=3, helper=2, earlier=earlier)
    assert system["role"] == "system" and user["role"] == "user"
    assert "Main agent: agent0" in system["content"]
    assert "agent1, agent2" in system["content"]
    assert '"none"' in system["content"]
    text = user["content"]
    order = _positions(
        text,
        [
            "worked example from a different domain",  # fixed barman example
            "pour-shaker-to-shot cocktail1 shot1",  # ... with its single-agent plan
            "final goal condition, stated with object names, is: shot2 contains cocktail2",
            DOMAIN_NL,  # current domain
            EXAMPLE_NL.splitlines()[0],  # its example task
            "pickup b\nstack b a",  # ... with its plan
            TASK_NL.splitlines()[0],  # the current task
            "agent1: b is on the table and the arm is empty",  # earlier subgoals
            "Propose the subgoal of agent2 only",
        ],
    )
    assert order == sorted(order)
    assert text.rstrip().endswith("agent2:")
    assert not LEFTOVER.search(system["content"] + text)


def test_first_helper_prompt_and_no_fixed_example(task: BenchmarkTask) -> None:
    _, user = generator_messages(task, agents=2, helper=1, fixed_example=False)
    assert "none yet: agent1 is the first helper" in user["content"]
    assert "cocktail" not in user["content"]
    with pytest.raises(ValueError, match=r"helper must be in 1\.\.1"):
        generator_messages(task, agents=2, helper=2)


def test_translator_prompt(task: BenchmarkTask) -> None:
    system, user = translator_messages(task, "b is on the table and the arm is empty")
    assert "PDDL goal only" in system["content"]
    text = user["content"]
    order = _positions(
        text,
        [
            "(:objects a b c)",
            "(on b c)",  # the initial state
            "Your goal is to rearrange the blocks",  # the task's own English goal ...
            "(:goal\n  (and\n    (on a b)\n    (on c a)))",  # ... with its PDDL goal
            "b is on the table and the arm is empty",
            "The new goal in PDDL:",
        ],
    )
    assert order == sorted(order)
    assert text.count("(:goal") == 1  # the problem is shown without its goal
    assert "You have 3 blocks" not in text  # only the goal part of the English text
    assert not LEFTOVER.search(system["content"] + text)


def test_fixed_barman_example_plan_is_valid(tmp_path: Path) -> None:
    """The plan in the fixed example solves its task in the project's barman domain."""
    domain = REPO / "twostep" / "generators" / "domains" / "barman.pddl"
    if not domain.is_file():
        pytest.skip("barman domain not available")
    problem_file = tmp_path / "p.pddl"
    problem_file.write_text(
        "(define (problem fixed) (:domain barman)"
        " (:objects left right - hand shaker1 - shaker shot1 shot2 - shot"
        " ingredient1 ingredient2 ingredient3 - ingredient cocktail1 - cocktail"
        " dispenser1 dispenser2 dispenser3 - dispenser l0 l1 l2 - level)"
        " (:init (handempty left) (handempty right) (ontable shaker1) (ontable shot1)"
        " (ontable shot2) (clean shaker1) (clean shot1) (clean shot2) (empty shaker1)"
        " (empty shot1) (empty shot2) (shaker-empty-level shaker1 l0) (shaker-level shaker1 l0)"
        " (next l0 l1) (next l1 l2) (dispenses dispenser1 ingredient1)"
        " (dispenses dispenser2 ingredient2) (dispenses dispenser3 ingredient3)"
        " (cocktail-part1 cocktail1 ingredient2) (cocktail-part2 cocktail1 ingredient1))"
        " (:goal (contains shot1 cocktail1)))"
    )
    problem = load_problem(domain, problem_file)
    text = template("generator_example").template
    plan = text.split("with these steps:\n", 1)[1].split("\n\n", 1)[0].splitlines()
    final = simulate(problem.init, Grounder(problem).ground_plan(plan))
    assert problem.goal.holds(final)
    assert parse_goal("(and (handempty left) (handempty right))", problem).holds(final)


def test_cli_prints_both_prompts(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    root = make_blocksworld_data(tmp_path)
    argv = ["--domain", "blocksworld", "--task", "1", "--agents", "3", "--helper", "2"]
    assert prompts_main([*argv, "--data", str(root)]) == 0
    out = capsys.readouterr().out
    assert "subgoal generator, agent2: system" in out
    assert "agent1: <the subgoal generated for agent1>" in out
    assert "translator: user" in out
    assert "a is on top of b" in out  # example subgoal taken from the task's goal


def test_cli_unknown_domain_and_task(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    root = str(make_blocksworld_data(tmp_path))
    assert prompts_main(["--domain", "nope", "--task", "1", "--data", root]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("twostep-prompts: error: unknown domain 'nope'") and "\n" not in err
    assert prompts_main(["--domain", "blocksworld", "--task", "9", "--data", root]) == 2
    assert "unknown task 9" in capsys.readouterr().err


def test_cli_on_generated_data(data_root: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["--domain", "blocksworld", "--task", "5", "--agents", "3", "--data", str(data_root)]
    assert prompts_main(argv) == 0
    out = capsys.readouterr().out
    assert "Propose the subgoal of agent1 only" in out and not LEFTOVER.search(out)


def test_derived_facts_and_goal_formulas_are_shown_as_pddl_allows() -> None:
    from tests.examples import GRAPH, GRAPH_PROBLEM
    from twostep.llm.prompts import goal_block, problem_state_pddl
    from twostep.pddl import Goal, parse_problem

    problem = parse_problem(GRAPH, GRAPH_PROBLEM)
    assert ("reach", "n2") in problem.init  # the state holds the derived facts ...
    state = problem_state_pddl(problem)
    assert "(reach" not in state and "(cut-off" not in state  # ... PDDL's :init never does
    assert "(open n1 n2)" in state
    formula = ["exists", ["?a"], ["visited", "?a"]]
    assert "(exists (?a) (visited ?a))" in goal_block(Goal(formula=formula))
