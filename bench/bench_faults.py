"""Fault-injection bench: a 20-job sweep through an LLM that fails, killed twice with kill -9.

The sweep (``twostep -m domain=blocksworld task=range(1,21) method=twostep decomposer=llm``)
asks its LLM questions of the stand-in server of ``tests/llm_standin.py`` on 127.0.0.1
(``llm=openai-compatible llm.model=openai/standin``), which answers each request at
random with a rate limit (429), a server error (500/503), a delay longer than the
client's timeout, a junk answer, or "none" (no further helper subgoal). Twice, at a
random moment, the sweep's process gets SIGKILL and the same command is started again;
the third start runs to the end. Then, from the sweeps' job records, the job store and
the MLflow store:

    jobs completed      jobs of the last sweep that finished (goal: all 20)
    jobs recomputed     job keys whose finished result was computed more than once (goal: 0)
    MLflow duplicates   job runs beyond one per job key (goal: 0)
    stored failures     results in the job store that are not a finished job (goal: 0)

    .venv/bin/python bench/bench_faults.py                    # 20 jobs, 2 kills, seed 0
    .venv/bin/python bench/bench_faults.py --jobs 10 --kills 1 --prefect --seed 3

Prefect is off by default (``orchestration.prefect=false``: the bench is about the
failures, not the server start); ``--prefect`` runs the jobs as flows on the sweep's server.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import json
import random
import signal
import socketserver
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from tests.llm_standin import Fault, Reply, standin_server  # noqa: E402

TWOSTEP = Path(sys.executable).parent / "twostep"
JUNK = "As an AI model I cannot ```pddl (:goal (and (on-table"  # unparseable on purpose
CLIENT_TIMEOUT_S = 2.0


class FaultyLLM:
    """Replies for the stand-in: a fault or junk with the given probabilities, else "none"."""

    def __init__(self, seed: int, rate: float) -> None:
        self.random = random.Random(seed)
        self.rate = rate
        self.counts: collections.Counter[str] = collections.Counter()
        self.lock = threading.Lock()

    def reply(self) -> tuple[str, Reply]:
        with self.lock:
            roll = self.random.random()
            kind: str
            reply: Reply
            if roll < self.rate:
                kind, reply = "rate limit (429)", Fault(status=429)
            elif roll < 2 * self.rate:
                status = self.random.choice((500, 503))
                kind, reply = "server error (5xx)", Fault(status=status)
            elif roll < 2.5 * self.rate:
                kind, reply = "timeout", Fault(delay_s=CLIENT_TIMEOUT_S + 1.0)
            elif roll < 3.5 * self.rate:
                kind, reply = "junk answer", JUNK
            else:
                kind, reply = "answer", "none"
            self.counts[kind] += 1
            return kind, reply


def sweep_command(data: Path, out: Path, jobs: int, api_base: str, prefect: bool) -> list[str]:
    return [
        str(TWOSTEP), "-m", "domain=blocksworld", f"task=range(1,{jobs + 1})", "agents=2",
        "method=twostep", "decomposer=llm", "llm=openai-compatible", "llm.model=openai/standin",
        f"llm.api_base={api_base}", "llm.api_key_env=null", f"llm.timeout_s={CLIENT_TIMEOUT_S}",
        "llm.max_retries=4", "llm.backoff_s=0.1", "planner.time_limit_s=20",
        f"orchestration.prefect={'true' if prefect else 'false'}",
        f"data.root={data}", f"output.root={out}",
    ]  # fmt: skip


def records(out: Path) -> list[dict[str, Any]]:
    found = []
    for path in sorted(out.glob("multiruns/*/*/.twostep/jobs/*.json")):
        with contextlib.suppress(OSError, ValueError):  # a record being written
            found.append(json.loads(path.read_text()))
    return found


def computed(out: Path) -> int:
    return sum(1 for r in records(out) if not r.get("reused"))


def run_until_killed(command: list[str], out: Path, after: int, rng: random.Random) -> str:
    """Start the sweep; kill -9 it once it computed ``after`` more jobs (reused ones do
    not count), plus a random fraction of a second to land inside the next job."""
    before, seen = computed(out), len(records(out))
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        while computed(out) < before + after and process.poll() is None:
            time.sleep(0.05)
        time.sleep(rng.uniform(0.0, 1.0))
        if process.poll() is None:
            process.send_signal(signal.SIGKILL)
        process.wait()
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    new = computed(out) - before
    return f"{len(records(out)) - seen} job(s) finished, {new} of them computed"


def mlflow_counts(out: Path) -> tuple[int, int]:
    """(job runs, duplicates: runs beyond one per job key) in the MLflow store."""
    from mlflow.tracking import MlflowClient

    client = MlflowClient(f"sqlite:///{out}/mlflow.db")
    keys: collections.Counter[str] = collections.Counter()
    for experiment in client.search_experiments():
        for run in client.search_runs([experiment.experiment_id], max_results=10000):
            if run.data.tags.get("twostep.kind") == "job":
                keys[run.data.tags.get("twostep.job_key", run.info.run_id)] += 1
    return sum(keys.values()), sum(n - 1 for n in keys.values())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=20)
    parser.add_argument("--kills", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--fault-rate", type=float, default=0.15, help="per fault kind")
    parser.add_argument("--prefect", action="store_true")
    parser.add_argument("--data", type=Path, default=REPO / "data")
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--save", type=Path, default=None, help="also write the table here")
    args = parser.parse_args()

    rng = random.Random(args.seed)
    out = args.out or Path(tempfile.mkdtemp(prefix="bench-faults-")) / "out"
    llm = FaultyLLM(args.seed, args.fault_rate)
    start = time.perf_counter()
    lines: list[str] = []
    # A client that gave up on a delayed answer closes its socket: not worth a traceback.
    socketserver.BaseServer.handle_error = lambda self, request, address: None  # type: ignore[method-assign]
    with standin_server() as server:
        server.next_reply = lambda request, authorization: llm.reply()[1]  # type: ignore[method-assign]
        command = sweep_command(args.data, out, args.jobs, server.api_base, args.prefect)
        for kill in range(args.kills):
            finished = run_until_killed(command, out, rng.randint(3, 6), rng)
            lines.append(f"start {kill + 1}: killed with SIGKILL after {finished}")
        final = subprocess.run(command, capture_output=True, text=True, timeout=3600)
    wall = time.perf_counter() - start
    summaries = sorted(out.glob("multiruns/*/*/.twostep/summary.json"))
    summary = json.loads(summaries[-1].read_text()) if summaries else {}
    computations: collections.Counter[str] = collections.Counter()
    for record in records(out):
        if not record.get("reused") and record.get("status") == "success":
            computations[str(record.get("job_key"))] += 1
    stored = [json.loads(p.read_text()) for p in out.glob("jobs/*/result.json")]
    stored_failures = sum(1 for r in stored if r.get("status") in ("llm_error", "error"))
    runs, duplicates = mlflow_counts(out) if (out / "mlflow.db").is_file() else (0, 0)
    faults = {k: v for k, v in llm.counts.items() if k != "answer"}
    lines += [
        f"start {args.kills + 1}: ran to the end (exit {final.returncode})",
        "",
        f"{'jobs':<22}{args.jobs}",
        f"{'jobs completed':<22}{summary.get('jobs_done', 0) - summary.get('jobs_failed', 0)}"
        f" (failed {summary.get('jobs_failed', '?')}, reused {summary.get('jobs_reused', '?')})",
        f"{'jobs recomputed':<22}{sum(1 for n in computations.values() if n > 1)}",
        f"{'MLflow job runs':<22}{runs}",
        f"{'MLflow duplicates':<22}{duplicates}",
        f"{'stored failures':<22}{stored_failures}",
        f"{'LLM requests':<22}{sum(llm.counts.values())}",
        f"{'faults injected':<22}"
        + (", ".join(f"{n} {k}" for k, n in sorted(faults.items())) or "none"),
        f"{'wall time':<22}{wall:.0f} s ({args.kills + 1} starts, "
        f"prefect {'on' if args.prefect else 'off'}, seed {args.seed})",
    ]
    if final.returncode != 0:
        lines.append("last start's output (tail):")
        lines += (final.stdout + final.stderr).strip().splitlines()[-10:]
    text = "\n".join(lines)
    print(text)
    if args.save:
        args.save.write_text(text + "\n")


if __name__ == "__main__":
    main()
