"""The repair of objects both files declare: a problem object that is a domain constant.

A small domain of our own declares the constant ``key``; problems that declare ``key``
again (same type, untyped, typed ``object``) are read as the task the domain alone
defines, i.e. the same problem without that object. Checked against that problem as
written without the duplicate, by twostep's simulator and by the independent validator
(Fast Downward's grounding + unified-planning) on the files as written. A problem giving
``key`` another type is an error naming the file, the object and both types.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from checkers import IndependentValidator
from twostep.pddl import PDDLError, load_problem, parse_problem
from twostep.planner import PlannerSettings, plan
from twostep.plans.simulate import Grounder, simulate

DOMAIN = """; a robot fetches the key of the house and opens the cellar door with it
(define (domain cellar)
  (:requirements :strips :typing)
  (:types tool room door)
  (:constants key - tool)
  (:predicates (robot-at ?r - room) (lies ?t - tool ?r - room) (holds ?t - tool)
               (connects ?d - door ?from - room ?to - room) (locked ?d - door))
  (:action walk
    :parameters (?from - room ?to - room ?d - door)
    :precondition (and (robot-at ?from) (connects ?d ?from ?to) (not (locked ?d)))
    :effect (and (robot-at ?to) (not (robot-at ?from))))
  (:action take
    :parameters (?t - tool ?r - room)
    :precondition (and (robot-at ?r) (lies ?t ?r))
    :effect (and (holds ?t) (not (lies ?t ?r))))
  (:action unlock
    :parameters (?d - door ?from - room ?to - room)
    :precondition (and (robot-at ?from) (connects ?d ?from ?to) (holds key))
    :effect (not (locked ?d))))
"""


def problem(key_declaration: str) -> str:
    """Hall, kitchen and cellar; the key lies in the kitchen, the cellar door is locked."""
    return f"""(define (problem fetch-key)
  (:domain cellar)
  (:objects hall kitchen cellar - room  d1 d2 - door {key_declaration})
  (:init (robot-at hall) (lies key kitchen)
         (connects d1 hall kitchen) (connects d1 kitchen hall)
         (connects d2 hall cellar) (locked d2))
  (:goal (and (robot-at cellar))))
"""


AS_DOMAIN_DEFINES = problem("")  # the task without the duplicate declaration


def write(folder: Path, domain: str, task: str) -> tuple[Path, Path]:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "domain.pddl").write_text(domain)
    (folder / "p01.pddl").write_text(task)
    return folder / "domain.pddl", folder / "p01.pddl"


@pytest.mark.parametrize("declaration", ["key - tool", "key", "key - object"])
def test_a_constant_the_problem_declares_again_is_the_domain_constant(
    declaration: str, tmp_path: Path
) -> None:
    repaired = load_problem(*write(tmp_path, DOMAIN, problem(declaration)))
    alone = parse_problem(DOMAIN, AS_DOMAIN_DEFINES)
    assert "key" not in repaired.objects and repaired.domain.constants == {"key": "tool"}
    assert repaired.all_objects == alone.all_objects
    assert (repaired.init, repaired.goal) == (alone.init, alone.goal)
    # the planner is handed the repaired text, which declares key once
    assert "key" not in repaired.text.split("(:init")[0].split("(:objects")[1]


def test_a_plan_of_the_repaired_task_is_valid_on_the_task_the_domain_defines(
    tmp_path: Path,
) -> None:
    repaired = load_problem(*write(tmp_path / "twice", DOMAIN, problem("key - tool")))
    result = plan(repaired, PlannerSettings("lama-first", 20))
    assert result.solved and result.plan, result.message
    steps = list(result.plan)
    assert any(step.startswith("(unlock") for step in steps)  # the key is needed
    # twostep's simulator, on the task read without any repair
    alone = parse_problem(DOMAIN, AS_DOMAIN_DEFINES)
    assert alone.goal.holds(simulate(alone.init, Grounder(alone).ground_plan(steps)))
    # the independent checkers, on the files as written without the duplicate
    verdict = IndependentValidator(*write(tmp_path / "once", DOMAIN, AS_DOMAIN_DEFINES))
    checked = verdict.check_plan(steps)
    assert checked.valid, checked.reason
    assert "unified-planning" in checked.checkers and "simulator" in checked.checkers
    # and a plan that skips the key is not (the validators are not saying yes to anything)
    assert not verdict.check_plan([s for s in steps if not s.startswith("(take")]).valid


@pytest.mark.parametrize(
    ("declaration", "type_text"),
    [("key - room", "room"), ("key - (either room door)", "(either room door)")],
)
def test_a_constant_the_problem_types_otherwise_is_an_error(
    declaration: str, type_text: str, tmp_path: Path
) -> None:
    domain_file, problem_file = write(tmp_path, DOMAIN, problem(declaration))
    with pytest.raises(PDDLError) as raised:
        load_problem(domain_file, problem_file)
    message = str(raised.value)
    assert str(problem_file) in message and "'key'" in message
    assert f"'{type_text}'" in message and "'tool'" in message


def test_a_task_the_translator_rejects_names_its_files(tmp_path: Path) -> None:
    # The problem names another domain: our reader lets it through, Fast Downward's
    # translator refuses it; the error says which files, not "<pddl>".
    other = problem("key - tool").replace("(:domain cellar)", "(:domain basement)")
    domain_file, problem_file = write(tmp_path, DOMAIN, other)
    with pytest.raises(PDDLError) as raised:
        load_problem(domain_file, problem_file)
    message = str(raised.value)
    assert message.startswith(f"{problem_file} (domain {domain_file}): ")
    assert "translator rejects the task" in message and "basement" in message
