"""One outcome vocabulary (twostep/util/outcome.py): every status enum and the sets derived
from them live there, their values are the strings result.json, MLflow and the job store
hold, and no module of the library or ``flows/`` compares a value with a bare status string.

The scan reads the sources with :mod:`ast` here (not with bench/bench_structure.py), and is
shown to find a planted comparison."""

from __future__ import annotations

import ast
from enum import StrEnum
from pathlib import Path

import pytest

from tools.status_scan import bare_status_comparisons
from twostep.util import outcome

ROOT = Path(__file__).resolve().parent.parent
OUTCOME = ROOT / "twostep" / "util" / "outcome.py"

# "none" is also the LLM's answer kind and a CLI value ("no limit"), not only a status.
NOT_ONLY_STATUS = {"none"}


def _status_words() -> set[str]:
    words = {str(w) for w in outcome.STATUS_SYNONYMS}
    for value in vars(outcome).values():
        if isinstance(value, type) and issubclass(value, StrEnum) and value is not StrEnum:
            words |= {m.value for m in value}
    return words - NOT_ONLY_STATUS


def test_no_bare_status_comparison_outside_the_outcome_module() -> None:
    words = _status_words()
    found = []
    for package in ("twostep", "flows"):
        for path in sorted((ROOT / package).rglob("*.py")):
            if path == OUTCOME:
                continue
            for line, word in bare_status_comparisons(path.read_text(), words):
                found.append(f"{path.relative_to(ROOT)}:{line} {word!r}")
    assert not found, "\n".join(found)


def test_the_scan_finds_a_planted_comparison() -> None:
    planted = """
def f(result, runs, statuses, found):
    if result.get("status") == "timeout":
        return 1
    if "error" in result:  # a key, not a status
        return 2
    if found.tags.get("twostep.status") in ("success", "timeout"):
        return 3
    if "discarded" != statuses[0]:
        return 4
    return runs["status"].isin(["failed"]).sum() + statuses.count("accepted")
"""
    assert bare_status_comparisons(planted, _status_words()) == [
        (3, "timeout"),
        (7, "success"),
        (7, "timeout"),
        (9, "discarded"),
        (11, "accepted"),
        (11, "failed"),
    ]


def test_no_status_enum_is_defined_outside_the_outcome_module() -> None:
    defined = []
    for package in ("twostep", "flows"):
        for path in sorted((ROOT / package).rglob("*.py")):
            if path == OUTCOME:
                continue
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.ClassDef) and node.name.endswith("Status"):
                    defined.append(f"{path.relative_to(ROOT)}:{node.name}")
                if isinstance(node, ast.Assign | ast.AnnAssign):
                    targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                    defined += [
                        f"{path.relative_to(ROOT)}:{t.id}"
                        for t in targets
                        if isinstance(t, ast.Name) and t.id.endswith("STATUSES")
                    ]
    assert not defined, defined


def test_the_old_names_are_the_outcome_enums() -> None:
    from flows.status import JobStatus
    from twostep.embodied.executor import EmbodiedStatus
    from twostep.methods import RunStatus
    from twostep.planner import Status
    from twostep.plans.subgoals import SubgoalStatus

    assert Status is outcome.PlannerStatus
    assert RunStatus is outcome.RunStatus
    assert JobStatus is outcome.JobStatus
    assert SubgoalStatus is outcome.SubgoalStatus
    assert EmbodiedStatus is outcome.EmbodiedStatus


def test_the_stored_words_are_unchanged() -> None:
    """The strings result.json, MLflow's tags and the job store hold (written out here)."""
    assert [s.value for s in outcome.PlannerStatus] == [
        "solved", "timeout", "unsolvable", "incomplete", "error"
    ]  # fmt: skip
    assert [s.value for s in outcome.RunStatus] == [
        "solved", "timeout", "unsolvable", "incomplete", "error", "llm_error",
        "embodied_failed", "failed", "resource_limit",
    ]  # fmt: skip
    assert [s.value for s in outcome.JobStatus] == ["success", "failed", "timeout"]
    assert outcome.REPORT_STATUSES == ("success", "failed", "timeout", "running")
    assert [s.value for s in outcome.ExchangeStatus] == ["ok", "none", "discarded"]
    assert str(outcome.RunStatus.LLM_ERROR) == "llm_error"
    assert f"{outcome.JobStatus.TIMEOUT}" == "timeout"


def test_the_derived_sets() -> None:
    assert {"error", "llm_error", "failed", "resource_limit"} == outcome.UNFINISHED
    assert [s for s in outcome.RunStatus if outcome.storable(s)] == [
        "solved", "timeout", "unsolvable", "incomplete", "embodied_failed"
    ]  # fmt: skip
    assert {"success", "timeout"} == outcome.SETTLED
    assert [outcome.limit_reached(s) for s in ("timeout", "solved", "resource_limit", None)] == [
        True, False, False, False
    ]  # fmt: skip


@pytest.mark.parametrize(
    ("word", "meant"),
    [
        ("success", "success"), ("succeeded", "success"), ("solved", "success"),
        ("ok", "success"), ("finished", "success"), ("failed", "failed"),
        ("failure", "failed"), ("error", "failed"), ("unsolvable", "failed"),
        ("killed", "failed"), ("crashed", "failed"), ("timeout", "timeout"),
        ("timed_out", "timeout"), ("timed-out", "timeout"), ("running", "running"),
        ("scheduled", "running"),
    ],
)  # fmt: skip
def test_the_report_reads_each_stored_spelling(word: str, meant: str) -> None:
    from twostep.report.runs import normalise_status

    assert len(outcome.STATUS_SYNONYMS) == 16
    assert normalise_status(word) == meant
    assert normalise_status(word.upper()) == meant
    assert type(normalise_status(word)) is str  # a plain string in the run table and its CSV
