"""The ``twostep`` command on bad input: one clear line, non-zero exit, no traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from tests.conftest import BLOCKS_DOMAIN

REPO = Path(__file__).resolve().parent.parent


def run_cli(*overrides: str, cwd: Path = REPO) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "flows.cli", "orchestration.prefect=false", "mlflow.enabled=false", *overrides],
        capture_output=True, text=True, cwd=cwd, timeout=240,
    )  # fmt: skip


def test_malformed_pddl_names_file_and_line(tmp_path: Path) -> None:
    folder = tmp_path / "data" / "blocks"
    folder.mkdir(parents=True)
    (folder / "domain.pddl").write_text(BLOCKS_DOMAIN)
    (folder / "p01.pddl").write_text(
        "(define (problem p) (:domain blocks)\n (:objects a b)\n (:init (on-table a) (on a q))\n (:goal (on a b)))\n"
    )
    proc = run_cli(
        f"data.root={tmp_path / 'data'}",
        f"output.root={tmp_path / 'out'}",
        "domain.name=blocks",
        "task=1",
        "method=sa",
    )
    assert proc.returncode != 0
    assert f"{folder / 'p01.pddl'}:3:" in proc.stdout + proc.stderr
    assert "Traceback" not in proc.stdout + proc.stderr


def test_unknown_domain_lists_the_domains(tmp_path: Path) -> None:
    proc = run_cli(f"output.root={tmp_path}", "domain.name=blockworld", "method=sa")
    assert proc.returncode != 0
    out = proc.stdout + proc.stderr
    assert (
        "unknown domain 'blockworld'" in out
        and "barman, blocksworld, grippers, termes, tyreworld" in out
    )
    assert "Traceback" not in out
