"""The cache of parsed problems (``load_problem(..., cache_dir)``): the same model as a
fresh parse, used instead of parsing, and never stale after an edit."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.examples import task_files
from twostep.pddl import PDDLError, Problem, domain_to_pddl, load_problem, problem_to_pddl
from twostep.pddl import reader as pddl_reader


def same(a: Problem, b: Problem) -> bool:
    return (
        domain_to_pddl(a.domain) == domain_to_pddl(b.domain)
        and problem_to_pddl(a) == problem_to_pddl(b)
        and a.domain.actions == b.domain.actions
        and list(a.domain.predicates.items()) == list(b.domain.predicates.items())
        and (a.init, a.goal, a.source, a.domain.source)
        == (b.init, b.goal, b.source, b.domain.source)
    )


def test_a_cached_problem_is_the_parsed_one_and_skips_parsing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    domain, problem = task_files(tmp_path)
    fresh = load_problem(domain, problem)
    first = load_problem(domain, problem, tmp_path / "cache")
    assert len(list((tmp_path / "cache").glob("*.pickle"))) == 1
    assert same(first, fresh)

    def no_parsing(*args: object) -> Problem:
        raise AssertionError("parsed although cached")

    monkeypatch.setattr(pddl_reader, "parse_problem", no_parsing)
    again = load_problem(domain, problem, tmp_path / "cache")
    assert same(again, fresh)


def test_an_edited_file_is_parsed_again(tmp_path: Path) -> None:
    domain, problem = task_files(tmp_path)
    load_problem(domain, problem, tmp_path / "cache")
    task_files(tmp_path, goal="(on b a)")
    edited = load_problem(domain, problem, tmp_path / "cache")
    assert edited.goal.positive == {("on", "b", "a")}
    assert len(list((tmp_path / "cache").glob("*.pickle"))) == 2


def test_a_broken_entry_is_parsed_again_and_bad_pddl_still_raises(tmp_path: Path) -> None:
    domain, problem = task_files(tmp_path)
    load_problem(domain, problem, tmp_path / "cache")
    (entry,) = (tmp_path / "cache").glob("*.pickle")
    entry.write_bytes(b"not a pickle")
    assert load_problem(domain, problem, tmp_path / "cache").goal.positive == {("on", "a", "b")}
    problem.write_text("(define (problem p) (:domain blocks) (:init (on-table a)")
    with pytest.raises(PDDLError):
        load_problem(domain, problem, tmp_path / "cache")
    assert len(list((tmp_path / "cache").glob("*.pickle"))) == 1  # nothing stored for it
