"""Tests of the problem generators for the IPC sample's domains
(twostep/generators/ipc_sample.py, which bench/bench_deal_generated.py runs).

The generated files are read against the sample's own domain files (read in place, never
copied into the repository): by twostep's reader and by Fast Downward's translator (the
repo's loader). The object counts are counted from the parsed problem, not from what the
generator says it wrote; one small problem per domain is solved by the planner and its
plan checked by the independent validator.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest

from tests.support.skips import IPC_SAMPLE, needs_ipc_sample
from twostep.generators.ipc_sample import (
    AGENT_PREDICATES,
    SIZES,
    gen_barman,
    gen_blocks,
    gen_floortile,
    gen_gripper,
    gen_storage,
    gen_termes,
    gen_visitall,
)
from twostep.pddl import Problem, parse_problem
from twostep.pddl.translator import translate
from twostep.planner import PlannerSettings, plan_pddl


def _read(domain: str, text: str) -> Problem:
    """The problem read by twostep's reader, and by Fast Downward's translator, which must
    find its goal reachable (under the delete relaxation) and ground some actions."""
    domain_text = (IPC_SAMPLE / domain / "domain.pddl").read_text()
    problem = parse_problem(domain_text, text)
    translation = translate(domain_text, text)
    assert not translation.goal_unreachable
    assert "begin_operator" in translation.sas
    return problem


def _kinds(problem: Problem) -> Counter[str]:
    return Counter(problem.objects.values())


def _facts(problem: Problem, predicate: str) -> list[tuple[str, ...]]:
    return sorted(f for f in problem.init if f[0].lower() == predicate.lower())


@needs_ipc_sample
@pytest.mark.parametrize("domain", list(SIZES))
def test_every_size_parses_and_is_reproducible(domain: str) -> None:
    # every size of the bench, two seeds: both readers accept the file; a seed gives the
    # same file twice and another seed another file
    assert set(AGENT_PREDICATES) == set(SIZES)
    for _label, make in SIZES[domain]:
        first, second = make(1), make(2)
        assert make(1).text == first.text
        assert first.text != second.text
        for generated in (first, second):
            problem = _read(domain, generated.text)
            declared = {name for names in generated.objects.values() for name in names}
            assert set(problem.objects) == declared
            assert problem.goal.positive and not problem.goal.holds(problem.init)


@needs_ipc_sample
def test_blocks_and_gripper_counts() -> None:
    for n in (4, 9, 14):
        problem = _read("blocks", gen_blocks(n, 3).text)
        assert len(problem.objects) == n
        # towers: every block on the table or on exactly one block, one top per tower
        on = _facts(problem, "on")
        table = _facts(problem, "ontable")
        assert len(on) + len(table) == n and len(_facts(problem, "clear")) == len(table)
        assert len({f[1] for f in on}) == len(on) and len({f[2] for f in on}) == len(on)
    for n in (4, 11, 20):
        problem = _read("gripper", gen_gripper(n, 3).text)
        assert len(_facts(problem, "ball")) == n and len(_facts(problem, "room")) == 2
        assert len(_facts(problem, "gripper")) == 2 and len(_facts(problem, "at-robby")) == 1
        # every ball must change rooms
        start = {f[1]: f[2] for f in _facts(problem, "at")}
        assert all(start[f[1]] != f[2] for f in problem.goal.positive)
        assert len(problem.goal.positive) == n


def _grid_connected(cells: set[str], links: set[tuple[str, str]]) -> bool:
    start = min(cells)
    seen, todo = {start}, [start]
    while todo:
        cell = todo.pop()
        for a, b in links:
            if a == cell and b not in seen:
                seen.add(b)
                todo.append(b)
    return seen == cells


@needs_ipc_sample
@pytest.mark.parametrize(
    ("side", "holes", "half"), [(3, False, False), (5, True, True), (8, True, False)]
)
def test_visitall_grid(side: int, holes: bool, half: bool) -> None:
    problem = _read("visitall-sat11-strips", gen_visitall(side, 4, holes, half).text)
    cells = set(problem.objects)
    assert (len(cells) < side * side) if holes else (len(cells) == side * side)
    links = {(f[1], f[2]) for f in _facts(problem, "connected")}
    assert all((b, a) in links for a, b in links)  # both ways
    assert _grid_connected(cells, links)  # holes never cut the grid
    targets = {f[1] for f in problem.goal.positive}
    assert targets <= cells
    assert len(targets) == (len(cells) // 2 if half else len(cells))
    (robot,) = _facts(problem, "at-robot")
    assert ("visited", robot[1]) in problem.init


@needs_ipc_sample
@pytest.mark.parametrize(("cocktails", "shakers"), [(3, 1), (4, 2), (6, 3)])
def test_barman_counts_and_costs(cocktails: int, shakers: int) -> None:
    problem = _read("barman-sat11-strips", gen_barman(cocktails, shakers, 5).text)
    kinds = _kinds(problem)
    assert kinds["shaker"] == shakers and kinds["cocktail"] == cocktails
    assert kinds["shot"] == cocktails + 1 and kinds["hand"] == 2
    assert kinds["dispenser"] == kinds["ingredient"] >= 3
    assert len(problem.goal.positive) == cocktails
    assert {f[2] for f in problem.goal.positive} == {
        o for o, k in problem.objects.items() if k == "cocktail"
    }
    # the domain's action costs: the total cost starts at 0, the metric is in the file
    assert problem.numeric_init == (["=", ["total-cost"], "0"],)
    assert "(:metric minimize (total-cost))" in gen_barman(cocktails, shakers, 5).text
    for drink in (o for o, k in problem.objects.items() if k == "cocktail"):
        parts = [f[2] for f in problem.init if f[0].startswith("cocktail-part") and f[1] == drink]
        assert len(parts) == 2 and parts[0] != parts[1]


@needs_ipc_sample
@pytest.mark.parametrize(
    ("rows", "cols", "towers", "height"), [(3, 3, 1, 1), (4, 4, 2, 3), (5, 4, 3, 3)]
)
def test_termes_board(rows: int, cols: int, towers: int, height: int) -> None:
    problem = _read("termes-sat18-strips", gen_termes(rows, cols, towers, height, 6).text)
    kinds = _kinds(problem)
    assert kinds["position"] == rows * cols
    built = {f[1]: int(f[2][1:]) for f in problem.goal.positive if f[0] == "height"}
    assert len(built) == rows * cols
    tall = {p: h for p, h in built.items() if h > 0}
    assert len(tall) == towers and all(1 <= h <= height for h in tall.values())
    assert kinds["numb"] == max(tall.values()) + 1
    (depot,) = _facts(problem, "is-depot")
    (robot,) = _facts(problem, "at")
    r, c = map(int, depot[1].split("-")[1:])
    assert r in (0, rows - 1) or c in (0, cols - 1)  # on the border
    assert robot[1] == depot[1] and depot[1] not in tall
    assert ("has-block",) in problem.goal.negative
    assert all(f[2] == "n0" for f in _facts(problem, "height"))  # a flat board


@needs_ipc_sample
@pytest.mark.parametrize(("depots", "crates", "hoists"), [(1, 2, 1), (2, 4, 2), (2, 6, 3)])
def test_storage_counts(depots: int, crates: int, hoists: int) -> None:
    problem = _read("storage", gen_storage(depots, crates, hoists, 7).text)
    kinds = _kinds(problem)
    assert (kinds["depot"], kinds["crate"], kinds["hoist"]) == (depots, crates, hoists)
    at = _facts(problem, "at")
    assert len(at) == hoists and len({f[2] for f in at}) == hoists  # distinct areas
    assert len(_facts(problem, "available")) == hoists
    clear = {f[1] for f in _facts(problem, "clear")}
    assert not clear & {f[2] for f in at}  # a hoist's area is not clear
    # room in the depots for every crate beside the hoists
    depot_areas = {f[1] for f in _facts(problem, "in") if f[2].startswith("depot")}
    assert len(depot_areas) >= crates + hoists
    assert {f[1] for f in problem.goal.positive} == {
        o for o, k in problem.objects.items() if k == "crate"
    }


@needs_ipc_sample
@pytest.mark.parametrize(("rows", "cols"), [(3, 3), (4, 5)])
def test_floortile_grid(rows: int, cols: int) -> None:
    problem = _read("floortile-sat11-strips", gen_floortile(rows, cols, 8).text)
    kinds = _kinds(problem)
    assert kinds["tile"] == (rows + 1) * cols and kinds["robot"] == 2 and kinds["color"] == 2
    assert len(problem.goal.positive) == rows * cols
    colours = {f[2] for f in problem.goal.positive}
    assert colours == {"white", "black"}
    robots = {f[2] for f in _facts(problem, "robot-at")}
    assert len(robots) == 2 and not robots & {f[1] for f in _facts(problem, "clear")}
    assert len(_facts(problem, "clear")) == (rows + 1) * cols - 2


SMALL = {
    "blocks": gen_blocks(5, 1),
    "gripper": gen_gripper(4, 1),
    "visitall-sat11-strips": gen_visitall(3, 1, True, False),
    "barman-sat11-strips": gen_barman(3, 1, 1),
    "termes-sat18-strips": gen_termes(3, 3, 1, 2, 1),
    "storage": gen_storage(1, 2, 1, 1),
    "floortile-sat11-strips": gen_floortile(3, 3, 1),
}


@needs_ipc_sample
@pytest.mark.parametrize("domain", list(SMALL))
def test_a_small_problem_per_domain_is_solvable(domain: str, tmp_path: Path) -> None:
    # lama-first solves it; the plan is valid for the independent validator
    from checkers import IndependentValidator

    domain_path = IPC_SAMPLE / domain / "domain.pddl"
    text = SMALL[domain].text
    result = plan_pddl(domain_path.read_text(), text, PlannerSettings("lama-first", 30))
    assert result.plan is not None and len(result.plan) > 0, result
    problem_path = tmp_path / "p01.pddl"
    problem_path.write_text(text)
    verdict = IndependentValidator(domain_path, problem_path).check_plan(list(result.plan))
    assert verdict.valid, verdict
