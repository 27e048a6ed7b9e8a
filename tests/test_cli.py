"""The ``twostep`` command on bad input: one clear line, non-zero exit, no traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from tests.conftest import BLOCKS_DOMAIN
from tests.support.commands import REPO, run_cli


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


# ------------------------------------------------------------------ issue 37: refused at once

TWOSTEP = Path(sys.executable).parent / "twostep"  # the console script, MLflow logging on
CONF = REPO / "conf"


def error_lines(proc: subprocess.CompletedProcess[str]) -> list[str]:
    return [line for line in proc.stderr.splitlines() if line.strip()]


def test_a_typo_never_runs(tmp_path: Path) -> None:
    """Before: `agnets=2` printed Hydra's 7 lines ending in `use +agnets=2`, and
    `+agnets=3 ...` then ran N = 2 and logged it. Now one line naming the closest key, with
    or without `+`, in a sweep too, and nothing written."""
    domains = ", ".join(sorted(p.stem for p in (CONF / "domain").glob("*.yaml")))
    decomposers = ", ".join(sorted(p.stem for p in (CONF / "decomposer").glob("*.yaml")))
    agents = "error: unknown key 'agnets': did you mean 'agents'?"
    cases = [
        (["agnets=2"], agents),
        (["+agnets=3", "method=twostep", "decomposer=goal-split"], agents),
        (["++agnets=3"], agents),
        (["-m", "agnets=2,3", "task=1,2"], agents),
        (["orchestration.task_runer=dask"],
         "error: unknown key 'orchestration.task_runer': did you mean 'orchestration.task_runner'?"),
        (["domain=nosuch"], f"error: unknown domain 'nosuch' (choices: {domains})"),
        (["-m", "decomposer=goal-split,goalsplit"],
         f"error: unknown decomposer 'goalsplit' (choices: {decomposers})"),
    ]  # fmt: skip
    for arguments, line in cases:
        out = tmp_path / "out"
        proc = subprocess.run(
            [str(TWOSTEP), *arguments, f"output.root={out}"],
            capture_output=True, text=True, cwd=tmp_path, timeout=240,
        )  # fmt: skip
        assert proc.returncode == 2, (arguments, proc.stderr)
        assert error_lines(proc) == [line], arguments
        assert not out.exists() and not (tmp_path / "outputs").exists(), arguments


def test_a_bad_value_is_refused_before_any_folder_or_record(tmp_path: Path) -> None:
    """Before: `task=99`, `agents=0`, `score_mode=bogus` took 8-10 s and each left a run
    folder and a FAILED MLflow run. Now exit 2 with one line and nothing written: no run
    folder, no MLflow store (both would be under output.root); a sweep is refused for a
    value any of its jobs lists, before its folder exists."""
    cases = [
        (["task=99"], "error: unknown task 99 of domain 'blocksworld'; tasks: 1..20"),
        (["agents=0"], "error: agents=0 must be at least 1"),
        (["score_mode=bogus"], "error: score_mode=bogus is not allowed (allowed: exact, paper)"),
        (["-m", "domain=grippers", "task=1,99"],
         "error: unknown task 99 of domain 'grippers'; tasks: 1..20"),
        (["-m", "agents=2,0"], "error: agents=0 must be at least 1"),
        (["-m", "agents=2,two"],
         "error: agents=two: Value 'two' of type 'str' could not be converted to Integer"),
    ]  # fmt: skip
    for arguments, line in cases:
        out = tmp_path / "out"
        proc = subprocess.run(
            [str(TWOSTEP), *arguments, f"output.root={out}", f"data.root={REPO / 'data'}"],
            capture_output=True, text=True, cwd=tmp_path, timeout=240,
        )  # fmt: skip
        assert proc.returncode == 2, (arguments, proc.stderr)
        assert error_lines(proc) == [line], arguments
        assert not out.exists(), arguments  # no folder, no mlflow.db, no job store


def test_a_sweep_counts_timeouts_and_hides_the_launchers_lines(
    tmp_path: Path, data_root: Path
) -> None:
    """One progress line per job whose counts add up (before: `0 failed` beside
    `FAILED (timeout ...)`), no `[HYDRA] Launching ...` lines unless hydra.verbose.
    termes p06's SA search runs out of a 1 s limit (p01 needs a fraction of it)."""
    common = [
        "-m",
        "domain=termes",
        "task=1,6",
        "method=sa",
        "planner.time_limit_s=1",
        "orchestration.prefect=false",
        "mlflow.enabled=false",
        f"data.root={data_root}",
    ]
    proc = subprocess.run(
        [str(TWOSTEP), *common, f"output.root={tmp_path / 'a'}"],
        capture_output=True, text=True, cwd=tmp_path, timeout=600,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr  # a timeout is no failure of the sweep
    progress = [line for line in proc.stdout.splitlines() if line.startswith("[")]
    assert len(progress) == 2
    assert progress[0].startswith("[1/2: 1 ok, 0 failed, 0 timed out")
    assert progress[1].startswith("[2/2: 1 ok, 0 failed, 1 timed out")
    assert "] termes-p06-sa-n1-s0 | TIMED OUT (" in progress[1]
    assert "sweep finished: 2/2 jobs: 1 ok, 0 failed, 1 timed out" in proc.stdout
    assert "[HYDRA]" not in proc.stdout + proc.stderr
    verbose = subprocess.run(
        [str(TWOSTEP), *common, f"output.root={tmp_path / 'a'}", "hydra.verbose=true"],
        capture_output=True, text=True, cwd=tmp_path, timeout=600,
    )  # fmt: skip
    assert verbose.returncode == 0, verbose.stderr
    assert "Launching 2 jobs" in verbose.stdout + verbose.stderr
