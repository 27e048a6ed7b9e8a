"""Issue 39, findings 13 and 14: every value of the structured config has its range
checked before any work (one table, ``flows.checks.VALUE_RULES``), and the docs' table of
ranges is that table. Before, `executor.max_steps=0` was stored as the job's embodied
failure and `stall_limit=0`, `backoff_radius=-1`, ... ran silently."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from flows.checks import VALUE_RULES, value_problems
from tests.support.commands import compose_config

REPO = Path(__file__).resolve().parent.parent
DOC = REPO / "docs" / "explanations" / "reliability.md"


def test_the_docs_table_of_ranges_is_value_rules() -> None:
    text = DOC.read_text().split("## Ranges checked before any work", 1)[1]
    rows = re.findall(r"^\| `([^`]+)` \| (.+) \|$", text, flags=re.MULTILINE)
    assert rows == [(rule.name, rule.allowed) for rule in VALUE_RULES]


@pytest.mark.parametrize(
    ("override", "expected"),
    [
        ("executor.max_steps=0", "executor.max_steps=0 must be at least 1"),
        ("executor.max_steps=-5", "executor.max_steps=-5 must be at least 1"),
        ("executor.stall_limit=0", "executor.stall_limit=0 must be at least 1"),
        ("executor.stall_limit=-1", "executor.stall_limit=-1 must be at least 1"),
        ("executor.backoff_radius=-1", "executor.backoff_radius=-1 must be at least 1"),
        ("executor.backoff_radius=0", "executor.backoff_radius=0 must be at least 1"),
        ("seed=-1", "seed=-1 must be >= 0"),
        ("llm.temperature=3", "llm.temperature=3.0 is out of range (allowed: 0 to 2)"),
        ("llm.temperature=-0.1", "llm.temperature=-0.1 is out of range (allowed: 0 to 2)"),
        ("llm.top_p=0", "llm.top_p=0.0 is out of range (allowed: > 0 to 1 or null)"),
        ("llm.top_p=1.5", "llm.top_p=1.5 is out of range (allowed: > 0 to 1 or null)"),
        ("llm.max_tokens=0", "llm.max_tokens=0 must be at least 1"),
        ("llm.backoff_s=-1", "llm.backoff_s=-1.0 is out of range (allowed: 0 to 1e+06)"),
        ("decomposer.link_degree=-1", "decomposer.link_degree=-1 must be >= 0"),
        ("decomposer.cut=sideways",
         "decomposer.cut=sideways is not allowed (allowed: free, holding, mover, best)"),
        ("orchestration.dask_workers=0", "orchestration.dask_workers=0 must be at least 1"),
        ("orchestration.prefect_log_level=LOUD",
         "orchestration.prefect_log_level=LOUD is not allowed "
         "(allowed: DEBUG, INFO, WARNING, ERROR, CRITICAL)"),
    ],
)  # fmt: skip
def test_an_out_of_range_value_is_named_with_what_is_allowed(override: str, expected: str) -> None:
    assert value_problems(compose_config("method=twostep", override)) == [expected]


@pytest.mark.parametrize(
    "override",
    ["executor.max_steps=null", "executor.max_steps=1", "executor.stall_limit=1",
     "executor.backoff_radius=1", "seed=0", "llm.temperature=0", "llm.temperature=2",
     "llm.top_p=1", "llm.top_p=null", "llm.backoff_s=0", "decomposer.link_degree=0",
     "decomposer.cut=free", "orchestration.prefect_log_level=ERROR"],
)  # fmt: skip
def test_the_edges_of_each_range_are_allowed(override: str) -> None:
    assert value_problems(compose_config("method=twostep", override)) == []


def test_an_executor_value_is_refused_before_any_folder(tmp_path: Path) -> None:
    out = tmp_path / "out"
    done = subprocess.run(
        [str(Path(sys.executable).parent / "twostep"), "domain=alfworld", "task=4",
         "executor.stall_limit=0", f"output.root={out}", "orchestration.prefect=false"],
        capture_output=True, text=True, cwd=REPO, timeout=240,
    )  # fmt: skip
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.splitlines() == ["error: executor.stall_limit=0 must be at least 1"]
    assert not out.exists()
