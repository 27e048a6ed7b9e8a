"""twostep.pddl: reading real-world files, errors with file and line, goals, writing."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import BLOCKS_DOMAIN, blocks_problem
from twostep.pddl import (
    PDDLError,
    domain_to_pddl,
    load_problem,
    parse_goal,
    parse_problem,
    problem_to_pddl,
)


def test_blocks_model() -> None:
    p = parse_problem(
        BLOCKS_DOMAIN,
        blocks_problem("(on-table a) (on b a) (clear b) (arm-empty)", "(on a b)", "a b"),
    )
    assert set(p.domain.actions) == {"pickup", "putdown", "stack", "unstack"}
    assert p.domain.predicates["on"] == ("object", "object")
    assert ("on", "b", "a") in p.init and ("arm-empty",) in p.init
    assert p.goal.positive == {("on", "a", "b")}
    stack = p.domain.actions["stack"]
    assert [str(a) for a in stack.delete] == ["(clear ?under)", "(holding ?b)"]


def test_quirky_tyreworld_is_read_as_is(quirks_root: Path) -> None:
    folder = quirks_root / "tyreworld"
    p = load_problem(folder / "domain.pddl", folder / "p01.pddl")
    # tools the domain uses but only the problem declares become typed constants
    assert p.domain.constants == {"jack": "tool", "pump": "tool", "wrench": "tool"}
    assert "wrench" not in p.objects and "wrench" in p.all_objects
    # an action and a predicate share the name "open"
    assert "open" in p.domain.actions and "open" in p.domain.predicates


def test_written_pddl_reads_back_identically(quirks_root: Path) -> None:
    folder = quirks_root / "tyreworld"
    p = load_problem(folder / "domain.pddl", folder / "p01.pddl")
    q = parse_problem(domain_to_pddl(p.domain), problem_to_pddl(p))
    assert q.init == p.init and q.goal == p.goal and q.all_objects == p.all_objects
    assert q.domain.actions == p.domain.actions


@pytest.mark.parametrize(
    ("problem_text", "line", "fragment"),
    [
        (
            "(define (problem p) (:domain blocks)\n(:objects a b)\n(:init (on-table a)\n(:goal (on a b)))",
            3,  # the (:init that is never closed, not the define on line 1
            "never closed",
        ),
        (
            "(define (problem p) (:domain blocks)\n(:objects a b)\n(:init (on-table z))\n(:goal (on a b)))",
            3,
            "z",
        ),
        ("(define (problem p) (:domain blocks)\n(:objects a b))\n(:init)", 3, "a ')' too many"),
    ],
)
def test_malformed_problem_names_file_and_line(
    tmp_path: Path, problem_text: str, line: int, fragment: str
) -> None:
    (tmp_path / "d.pddl").write_text(BLOCKS_DOMAIN)
    (tmp_path / "p.pddl").write_text(problem_text)
    with pytest.raises(PDDLError) as info:
        load_problem(tmp_path / "d.pddl", tmp_path / "p.pddl")
    assert info.value.source == str(tmp_path / "p.pddl")
    assert info.value.line == line
    assert fragment in str(info.value)


def test_malformed_domain_is_blamed_on_the_domain(tmp_path: Path) -> None:
    (tmp_path / "d.pddl").write_text(
        BLOCKS_DOMAIN.replace(":precondition (holding ?b)", ":precondition (holdin ?b)")
    )
    (tmp_path / "p.pddl").write_text(blocks_problem("(arm-empty)", "(arm-empty)"))
    with pytest.raises(PDDLError) as info:
        load_problem(tmp_path / "d.pddl", tmp_path / "p.pddl")
    assert info.value.source == str(tmp_path / "d.pddl")
    assert info.value.line is not None and info.value.line > 1


@pytest.mark.parametrize(
    ("where", "typo"),
    [
        ("(:predicates (clear ?x)", "(:types block)\n  (:predicates (clear ?x -block)"),
        (
            "(:action pickup :parameters (?b)",
            "(:types block)\n  (:action pickup :parameters (?b -block)",
        ),
    ],
    ids=["predicate", "parameters"],
)
def test_a_dash_glued_to_its_type_is_named_with_file_and_line(
    tmp_path: Path, where: str, typo: str
) -> None:
    # `?x -block` (no space after the dash): Fast Downward refuses it ("Expected a
    # variable"); read as a third name it would blame the problem's arity instead.
    domain = BLOCKS_DOMAIN.replace("(:requirements :strips)", "(:requirements :strips :typing)")
    assert where in domain
    (tmp_path / "d.pddl").write_text(domain.replace(where, typo, 1))
    (tmp_path / "p.pddl").write_text(blocks_problem("(arm-empty)", "(arm-empty)"))
    with pytest.raises(PDDLError) as info:
        load_problem(tmp_path / "d.pddl", tmp_path / "p.pddl")
    assert info.value.source == str(tmp_path / "d.pddl")
    lines = (tmp_path / "d.pddl").read_text().splitlines()
    assert info.value.line is not None and "-block" in lines[info.value.line - 1]
    assert "'-block' in a typed list" in str(info.value) and "'- block'" in str(info.value)


def test_parse_goal_checks_predicates_arity_objects() -> None:
    p = parse_problem(BLOCKS_DOMAIN, blocks_problem("(arm-empty)", "(on a b)", "a b"))
    g = parse_goal("(:goal (and (on-table a) (not (holding b))))", p)
    assert g.positive == {("on-table", "a")} and g.negative == {("holding", "b")}
    assert parse_goal("(on a b)", p).positive == {("on", "a", "b")}
    for text, fragment in [
        ("(and (stacked a b))", "unknown predicate 'stacked'"),
        ("(on a)", "takes 2"),
        ("(on a q)", "unknown object 'q'"),
        ("(and (on a b) (not (on a b)))", "negation"),
        ("", "empty"),
    ]:
        with pytest.raises(PDDLError, match=fragment):
            parse_goal(text, p)


def test_goal_holds_and_unmet() -> None:
    p = parse_problem(
        BLOCKS_DOMAIN, blocks_problem("(arm-empty) (on a b)", "(on a b) (not (holding a))", "a b")
    )
    assert p.goal.holds(p.init)
    assert p.goal.unmet(frozenset({("holding", "a")})) == ["(on a b)", "(not (holding a))"]


def test_action_costs_are_read_and_written_back() -> None:
    from tests.examples import DRIVE_OR_FLY, DRIVE_OR_FLY_PROBLEM, ROAD_COSTS

    problem = parse_problem(DRIVE_OR_FLY, DRIVE_OR_FLY_PROBLEM)
    assert {a.name: a.cost for a in problem.domain.actions.values()} == ROAD_COSTS
    domain_text, problem_text = domain_to_pddl(problem.domain), problem_to_pddl(problem)
    assert "(increase (total-cost) 12)" in domain_text
    assert "(:metric minimize (total-cost))" in problem_text
    again = parse_problem(domain_text, problem_text)
    assert {a.name: a.cost for a in again.domain.actions.values()} == ROAD_COSTS
    assert again.init == problem.init and again.goal == problem.goal
    # A domain without costs says nothing about them.
    blocks = parse_problem(
        BLOCKS_DOMAIN, blocks_problem("(on-table a) (clear a) (arm-empty)", "(holding a)")
    )
    assert not blocks.domain.has_action_costs
    assert "total-cost" not in domain_to_pddl(blocks.domain) + problem_to_pddl(blocks)


def test_reading_pddl_does_not_import_unified_planning(tmp_path: Path) -> None:
    # unified-planning is only the plan validator: reading, grounding (Fast Downward's
    # translator, a subprocess) and simulating need none of it, nor its engines' imports
    # (ConfigSpace, scipy: seconds per process; twostep-score only reads).
    import subprocess
    import sys

    from tests.conftest import REPO

    (tmp_path / "domain.pddl").write_text(BLOCKS_DOMAIN)
    (tmp_path / "problem.pddl").write_text(
        blocks_problem("(on-table a) (clear a) (arm-empty)", "(holding a)")
    )
    code = (
        "import sys; from twostep.pddl import load_problem; "
        f"p = load_problem({str(tmp_path / 'domain.pddl')!r}, {str(tmp_path / 'problem.pddl')!r}); "
        "print(len(p.domain.actions), sorted(m for m in sys.modules "
        "if m.startswith(('unified_planning', 'ConfigSpace'))))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, check=True
    ).stdout
    assert out.split() == ["4", "[]"]
