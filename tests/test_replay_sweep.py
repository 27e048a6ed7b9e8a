"""The whole replay chain through the real tools: a log in the official format (written
here) -> ``twostep-data import-answers`` -> ``twostep -m experiment=paper_replay`` (Hydra,
the sweep's Prefect server, MLflow) -> ``twostep-report`` -> Table I of the replay.

The log's numbers are chosen here (official length 5 on p01, 9 on p02); every schedule
of the sweep is re-validated by ``check_run`` and by the independent validator.
"""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from checkers import IndependentValidator
from tests.replay_logs import block
from twostep.methods import check_run
from twostep.methods.result import RunResult
from twostep.tasks.benchmark import load_task

pytestmark = [pytest.mark.integration, pytest.mark.slow]
BIN = Path(sys.executable).parent
PREDICATES = ["arm-empty", "holding"]


def tool(name: str, *args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(
        [str(BIN / name), *args], capture_output=True, text=True, cwd=cwd, timeout=900
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return done


def schedule_of(result: dict[str, Any]) -> RunResult:
    run = RunResult(
        domain=result["domain"],
        task=result["task"],
        method=result["method"],
        agents=result["agents"],
    )
    run.agent_order = list(result["agent_order"])
    run.plans = {a: list(p) for a, p in result["plans"].items()}
    run.schedule = [[(agent, action) for agent, action in step] for step in result["schedule"]]
    return run


def test_paper_replay_from_logs_to_table_one(tmp_path: Path, data_root: Path) -> None:
    log = tmp_path / "10_8_2_agent.txt"
    log.write_text(
        block("blocksworld", 1, ["b3 is clear and on the table."], length=5.0, sa_cost=8.0)
        + block("blocksworld", 2, ["b1 floats above b2."], length=9.0, sa_cost=10.0)
    )
    answers, out = tmp_path / "answers", tmp_path / "out"
    tool(
        "twostep-data", "import-answers", "--format", "twostep-official", str(log),
        "--tasks", str(data_root), "--out", str(answers), "--model", "gpt-4o", cwd=tmp_path,
    )  # fmt: skip
    done = tool(
        "twostep", "-m", "experiment=paper_replay", f"llm.bundle={answers}",
        f"data.root={data_root}", f"output.root={out}", cwd=tmp_path,
    )  # fmt: skip
    printed = done.stdout + done.stderr
    assert "sweep: 8 jobs" in printed  # 2 tasks x (SA, MA, TwoStep on the answers, plan-deal)
    assert "flow runs: 8 completed" in printed  # one Prefect flow per job, on the sweep's server

    results = [json.loads(p.read_text()) for p in sorted(out.glob("multiruns/*/*/*/result.json"))]
    assert len(results) == 8
    replayed = {r["task"]: r for r in results if r.get("decomposer") == "llm"}
    assert replayed[1]["answer_source"] == "replayed, model gpt-4o, 10_8_2_agent.txt:2"
    assert [s["status"] for s in replayed[1]["subgoals"]] == ["accepted"]
    # p02's answer says what no phrase of the domain says: a counted translation failure
    assert replayed[2]["translation"] == {"translator": "rules", "read": 0, "failed": 1}
    assert replayed[2]["subgoals"][0]["reason"].startswith("translation failed")
    for result in results:  # every schedule, by our simulator and by the independent one
        if not result.get("schedule"):
            continue
        task = load_task("blocksworld", result["task"], data_root)
        check_run(task.problem, schedule_of(result), PREDICATES)
        steps = [[tuple(a) for a in step] for step in result["schedule"]]
        verdict = IndependentValidator(task.domain_path, task.problem_path).check_schedule(
            result["agent_order"], result["plans"], steps, PREDICATES
        )
        assert verdict.valid, verdict.reason

    from mlflow.tracking import MlflowClient

    client = MlflowClient(f"sqlite:///{out}/mlflow.db")
    (experiment,) = [e for e in client.search_experiments() if e.name.startswith("sweep ")]
    runs = client.search_runs([experiment.experiment_id], "tags.`twostep.kind` = 'job'")
    llm_runs = [r for r in runs if r.data.params.get("decomposer.name") == "llm"]
    assert {(r.data.params["llm.mode"], r.data.params["llm.translator"]) for r in llm_runs} == {
        ("bundle", "rules")
    }
    assert sorted(r.data.metrics["subgoals_untranslated"] for r in llm_runs) == [0.0, 1.0]

    report = tmp_path / "report"
    tool("twostep-report", "--experiment", experiment.name, "--tracking-uri", f"sqlite:///{out}/mlflow.db",
         "--out", str(report), cwd=tmp_path)  # fmt: skip
    with (report / "replay_table1.csv").open() as handle:
        table = {(r["agents"], r["source"]): r for r in csv.DictReader(handle)}
    official, twostep = table[("2", "official")], table[("2", "twostep")]
    # both tasks are covered by every row: the official mean is the log's (5 + 9) / 2
    assert (official["tasks"], float(official["exec_length"]), float(official["sa_length"])) == (
        "2",
        7.0,
        9.0,
    )
    mean = sum(r["exec_length"] for r in replayed.values()) / 2
    assert float(twostep["exec_length"]) == pytest.approx(mean)
    assert (report / "replay_fig3.png").is_file() and "Table I" in (
        report / "replay.md"
    ).read_text()
