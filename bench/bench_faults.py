"""Fault bench: what a user's mishaps do to a sweep's records, and whether any command
shows a traceback. One table, one row per scenario, each in an output root of its own:

    llm-faults        a 20-job TwoStep-LLM sweep through a stand-in LLM server on 127.0.0.1
                      that answers at random with a rate limit (429), a server error
                      (500/503), a delay longer than the client's timeout, a junk answer or
                      "none"; killed with SIGKILL twice, then run to the end
    deleted-store     a 6-job sweep; `rm outputs/mlflow.db`; the same command again
    truncated-store   a 6-job sweep; the MLflow store truncated to 0 bytes; the same again
    concurrent        two identical 4-job sweeps started together (Prefect off)
    concurrent+svc    the same with `twostep-services up` (jobs as Prefect flows on them)
    bad-files         a corpus of bad files (binary, a byte-order mark, 20,000 nested
                      `(and`, a directory, not YAML, wrong arity, an undeclared type, an
                      action twice) through every console script that reads files
    hostile-inputs    inputs that used to hang or run away (issue 39): FIFOs, /dev/zero
                      and symlink loops as task files, expert.yaml, LLM script or kitchen;
                      a YAML alias bomb; a 100,000 x 100,000 or negative-size kitchen; a
                      type typo; an unknown scene; the explosive grounding (`boom`, 40
                      objects) under a low memory limit and a short time limit;
                      `agents=1000`; a '?' in output.root, a key in llm.model, an
                      executor value out of range; each must answer in one line with the right exit code
                      and store nothing wrong ("hangs": runs stopped by the bench's timeout)
    orphans           `kill -9`, SIGTERM and SIGINT of a job while it grounds `boom`:
                      processes and twostep-translate-* folders left ("completed": kills
                      that left nothing)

Columns (from the sweeps' job records, the job store and the MLflow store, read with
MLflow's own client):

    jobs              jobs of the sweep (bad-files: cases)
    completed         jobs the last sweep finished (bad-files: cases answered with one line
                      naming the file, or read as the file without its BOM)
    recomputed        job keys whose finished result was computed more than once (goal: 0)
    MLflow runs       job runs in the MLflow store
    duplicates        job runs beyond one per job key (goal: 0)
    missing           jobs the sweeps recorded whose run is not in the store (goal: 0)
    stored failures   results in the job store that are not a finished job (goal: 0)
    tracebacks        Python tracebacks in anything the commands printed (goal: 0)

    .venv/bin/python bench/bench_faults.py                          # every scenario
    .venv/bin/python bench/bench_faults.py --only bad-files,concurrent
    .venv/bin/python bench/bench_faults.py --only hostile-inputs,orphans
    .venv/bin/python bench/bench_faults.py --jobs 10 --kills 1 --seed 3 --only llm-faults
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import json
import os
import random
import shutil
import signal
import socketserver
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from evaluation.pages.faults import COLUMNS, Row, records  # noqa: E402
from tests import bad_files  # noqa: E402
from tests.llm_standin import Fault, Reply, standin_server  # noqa: E402
from tools import record as bench_record  # noqa: E402

BIN = Path(sys.executable).parent
TWOSTEP = BIN / "twostep"
DATA = REPO / "data"
JUNK = "As an AI model I cannot ```pddl (:goal (and (on-table"  # unparseable on purpose
CLIENT_TIMEOUT_S = 2.0
# A valid single-agent plan of blocksworld p01 (b3 off b1, b1 off b2, then b2 on b3, b1 on b2).
P01_PLAN = "".join(
    f"({step})\n"
    for step in ("unstack b3 b1", "putdown b3", "unstack b1 b2", "putdown b1", "pickup b2",
                 "stack b2 b3", "pickup b1", "stack b1 b2")
)  # fmt: skip
OFFLINE = ["method=twostep", "decomposer=goal-split", "agents=2", "planner.time_limit_s=20"]


def computed(out: Path) -> int:
    return sum(1 for r in records(out) if not r.get("reused"))


def last_summary(out: Path) -> dict[str, Any]:
    paths = sorted(out.glob("multiruns/*/*/.twostep/summary.json"), key=lambda p: p.stat().st_mtime)
    return json.loads(paths[-1].read_text()) if paths else {}


def store_keys(out: Path) -> collections.Counter[str]:
    """Job runs per job key in the output root's MLflow store."""
    keys: collections.Counter[str] = collections.Counter()
    if not (out / "mlflow.db").is_file():
        return keys
    from mlflow.tracking import MlflowClient

    client = MlflowClient(f"sqlite:///{out}/mlflow.db")
    for experiment in client.search_experiments():
        for run in client.search_runs([experiment.experiment_id], max_results=10000):
            if run.data.tags.get("twostep.kind") == "job":
                keys[run.data.tags.get("twostep.job_key", run.info.run_id)] += 1
    return keys


def sweep_row(scenario: str, out: Path, jobs: int, outputs: Sequence[str]) -> Row:
    """The table's columns for a sweep scenario, from what it left in ``out``."""
    summary = last_summary(out)
    computations: collections.Counter[str] = collections.Counter()
    recorded = set()
    for record in records(out):
        if record.get("job_key"):
            recorded.add(str(record["job_key"]))
        if not record.get("reused") and record.get("status") == "success":
            computations[str(record.get("job_key"))] += 1
    stored = [json.loads(p.read_text()) for p in out.glob("jobs/*/result.json")]
    keys = store_keys(out)
    return Row(
        scenario,
        jobs,
        int(summary.get("jobs_done", 0)) - int(summary.get("jobs_failed", 0)),
        recomputed=sum(1 for n in computations.values() if n > 1),
        runs=sum(keys.values()),
        duplicates=sum(n - 1 for n in keys.values()),
        missing=len(recorded - set(keys)),
        stored_failures=sum(1 for r in stored if r.get("status") in ("llm_error", "error")),
        tracebacks=sum(text.count("Traceback") for text in outputs),
    )


def run(command: list[str], **kwargs: Any) -> subprocess.CompletedProcess[str]:
    return subprocess.run(command, capture_output=True, text=True, timeout=3600, **kwargs)


def sweep(out: Path, *extra: str) -> list[str]:
    return [str(TWOSTEP), "-m", f"data.root={DATA}", f"output.root={out}", *OFFLINE, *extra]


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


def llm_sweep_command(data: Path, out: Path, jobs: int, api_base: str) -> list[str]:
    return [
        str(TWOSTEP), "-m", "domain=blocksworld", f"task=range(1,{jobs + 1})", "agents=2",
        "method=twostep", "decomposer=llm", "llm=openai-compatible", "llm.model=openai/standin",
        f"llm.api_base={api_base}", "llm.api_key_env=null", f"llm.timeout_s={CLIENT_TIMEOUT_S}",
        "llm.max_retries=4", "llm.backoff_s=0.1", "planner.time_limit_s=20",
        "orchestration.prefect=false", f"data.root={data}", f"output.root={out}",
    ]  # fmt: skip


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


def llm_faults(root: Path, args: argparse.Namespace) -> Row:
    out = root / "out"
    rng = random.Random(args.seed)
    llm = FaultyLLM(args.seed, args.fault_rate)
    notes = []
    # A client that gave up on a delayed answer closes its socket: not worth a traceback.
    socketserver.BaseServer.handle_error = lambda self, request, address: None  # type: ignore[method-assign]
    with standin_server() as server:
        server.next_reply = lambda request, authorization: llm.reply()[1]  # type: ignore[method-assign]
        command = llm_sweep_command(DATA, out, args.jobs, server.api_base)
        for kill in range(args.kills):
            finished = run_until_killed(command, out, rng.randint(3, 6), rng)
            notes.append(f"start {kill + 1}: killed with SIGKILL after {finished}")
        final = run(command)
    faults = {k: v for k, v in llm.counts.items() if k != "answer"}
    notes.append(
        f"start {args.kills + 1}: ran to the end (exit {final.returncode}); "
        f"{sum(llm.counts.values())} LLM requests, faults injected: "
        + (", ".join(f"{n} {k}" for k, n in sorted(faults.items())) or "none")
    )
    row = sweep_row("llm-faults", out, args.jobs, [final.stdout + final.stderr])
    row.notes = notes
    return row


def lost_store(root: Path, scenario: str, lose: Callable[[Path], None]) -> Row:
    out = root / "out"
    command = sweep(out, "domain=blocksworld,grippers", "task=1,2,3")
    first = run(command)
    lose(out / "mlflow.db")
    again = run(command)
    row = sweep_row(scenario, out, 6, [first.stdout + first.stderr, again.stdout + again.stderr])
    restored = sum(1 for path in out.glob("jobs/*/mlflow.json"))
    row.notes.append(
        f"{scenario}: first run exit {first.returncode}, re-run exit {again.returncode}; "
        f"{restored} jobs remember their run"
    )
    return row


def deleted_store(root: Path, args: argparse.Namespace) -> Row:
    return lost_store(root, "deleted-store", lambda store: store.unlink())


def truncated_store(root: Path, args: argparse.Namespace) -> Row:
    return lost_store(root, "truncated-store", lambda store: store.write_bytes(b""))


def two_sweeps_at_once(out: Path, scenario: str, *extra: str) -> Row:
    command = sweep(out, "domain=blocksworld", "task=1,2,3,4", *extra)
    processes = [
        subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        for _ in range(2)
    ]
    outputs = ["".join(p.communicate(timeout=3600)) for p in processes]
    row = sweep_row(scenario, out, 4, outputs)
    summaries = [json.loads(p.read_text()) for p in out.glob("multiruns/*/*/.twostep/summary.json")]
    row.completed = min(int(s["jobs_done"]) - int(s["jobs_failed"]) for s in summaries)
    row.notes.append(
        f"{scenario}: exits {[p.returncode for p in processes]}, "
        f"jobs reused per sweep {[s['jobs_reused'] for s in summaries]}"
    )
    return row


def concurrent(root: Path, args: argparse.Namespace) -> Row:
    return two_sweeps_at_once(root / "out", "concurrent", "orchestration.prefect=false")


def concurrent_services(root: Path, args: argparse.Namespace) -> Row:
    out = root / "out"
    services = BIN / "twostep-services"
    up = run([str(services), "up", "--root", str(out)])
    try:
        if up.returncode != 0:
            return Row("concurrent+svc", 4, 0, notes=[f"services did not start: {up.stderr}"])
        row = two_sweeps_at_once(out, "concurrent+svc")
    finally:
        run([str(services), "down", "--root", str(out)])
    row.tracebacks += (up.stdout + up.stderr).count("Traceback")
    return row


@dataclass(frozen=True)
class Case:
    """A console script on one spoiled file."""

    name: str
    command: list[str]
    spoiled: Path
    expected_exit: int = 2


def bad_file_cases(root: Path) -> list[Case]:
    """Set up every case under ``root``: the spoiled files and the commands that read them."""
    cases: list[Case] = []
    spoilers = {
        "binary": bad_files.binary,
        "bom": bad_files.with_bom,
        "deep": bad_files.deep,
        "directory": bad_files.directory,
    }
    pddl_only = {
        "wrong-arity": ("p01.pddl", bad_files.wrong_arity),
        "undeclared-type": ("p01.pddl", bad_files.undeclared_type),
        "action-twice": ("domain.pddl", bad_files.duplicate_action),
    }

    def data_root(tag: str) -> Path:
        folder = root / tag / "data"
        shutil.copytree(DATA / "blocksworld", folder / "blocksworld")
        return folder

    def twostep(tag: str, data: Path, *extra: str) -> list[str]:
        return [str(TWOSTEP), "task=1", f"data.root={data}", f"output.root={root / tag / 'out'}",
                "mlflow.enabled=false", "orchestration.prefect=false", *extra]  # fmt: skip

    targets = [(f, spoil, n) for f in ("p01.pddl", "domain.pddl") for n, spoil in spoilers.items()]
    targets += [(f, spoil, n) for n, (f, spoil) in pddl_only.items()]
    targets += [
        ("expert.yaml", bad_files.not_yaml, "not-yaml"),
        ("p01.nl", bad_files.binary, "binary"),
    ]
    for file, spoil, kind in targets:
        tag = f"twostep-{file}-{kind}"
        data = data_root(tag)
        spoil(data / "blocksworld" / file)
        extra = ["method=twostep", "decomposer=expert"] if file == "expert.yaml" else []
        # a byte-order mark is read as the file without it (twostep/util/files.py): a success
        cases.append(Case(tag, twostep(tag, data, *extra), data / "blocksworld" / file,
                          0 if kind == "bom" else 2))  # fmt: skip
    for role, file in (("domain", "domain.pddl"), ("problem", "p01.pddl"), ("plan", "a.plan")):
        for kind, spoil in [
            *spoilers.items(),
            *[(n, s) for n, (f, s) in pddl_only.items() if f == file],
        ]:
            if role == "plan" and kind == "deep":
                continue
            tag = f"score-{role}-{kind}"
            folder = root / tag
            folder.mkdir(parents=True)
            for name in ("domain.pddl", "p01.pddl"):
                shutil.copy(DATA / "blocksworld" / name, folder / name)
            (folder / "a.plan").write_text(P01_PLAN)
            spoil(folder / file)
            command = [str(BIN / "twostep-score"), str(folder / "domain.pddl"),
                       str(folder / "p01.pddl"), str(folder / "a.plan"), "--no-cache",
                       "--agent-predicates", "none"]  # fmt: skip
            cases.append(Case(tag, command, folder / file, 0 if kind == "bom" else 2))
    for kind, spoil in spoilers.items():
        tag = f"prompts-p01-{kind}"
        data = data_root(tag)
        spoil(data / "blocksworld" / "p01.pddl")
        command = [str(BIN / "twostep-prompts"), "--data", str(data), "--domain", "blocksworld",
                   "--task", "1"]  # fmt: skip
        cases.append(
            Case(tag, command, data / "blocksworld" / "p01.pddl", 0 if kind == "bom" else 2)
        )
    data = data_root("data-check")
    bad_files.binary(data / "blocksworld" / "p01.pddl")
    command = [str(BIN / "twostep-data"), "check", "--data", str(data), "--domain", "blocksworld"]
    cases.append(Case("data-check-binary", command, data / "blocksworld" / "p01.pddl", 1))
    out = root / "report-sweep" / "out"
    done = run(
        sweep(out, "method=sa", "task=1,2", "mlflow.enabled=false", "orchestration.prefect=false")
    )
    assert done.returncode == 0, done.stderr
    (sweep_dir,) = out.glob("multiruns/*/*")
    for name in ("result.json", ".hydra/config.yaml"):
        copy = root / f"report-{name.replace('/', '-')}"
        shutil.copytree(sweep_dir, copy)
        (job,) = [p for p in copy.iterdir() if p.name.startswith("0_")]
        bad_files.binary(job / name)
        command = [
            str(BIN / "twostep-report"),
            "--sweep-dir",
            str(copy),
            "--out",
            str(copy / "report"),
        ]
        cases.append(Case(f"report-{name}-binary", command, job / name))
    runs_csv = root / "runs.csv"
    bad_files.binary(runs_csv)
    command = [str(BIN / "twostep-report"), "--runs-csv", str(runs_csv), "--out", str(root / "r")]
    cases.append(Case("report-runs.csv-binary", command, runs_csv))
    record = root / "services" / "services.json"
    record.parent.mkdir()
    bad_files.binary(record)
    command = [str(BIN / "twostep-services"), "status", "--root", str(record.parent)]
    cases.append(Case("services-record-binary", command, record, 3))
    return cases


def bad_files_row(root: Path, args: argparse.Namespace) -> Row:
    cases = bad_file_cases(root)
    answered, tracebacks, notes = 0, 0, []
    for case in cases:
        done = run(case.command, cwd=root)
        output = done.stdout + done.stderr
        tracebacks += output.count("Traceback")
        errors = [line for line in done.stderr.splitlines() if line.strip()]
        if case.expected_exit == 2:
            ok = done.returncode == 2 and len(errors) == 1 and str(case.spoiled) in errors[0]
        else:
            ok = done.returncode == case.expected_exit and "Traceback" not in output
        answered += ok
        if not ok:
            shown = (errors or [output.strip()])[0][:160]
            notes.append(f"bad-files: {case.name}: exit {done.returncode}: {shown}")
    return Row("bad-files", len(cases), answered, tracebacks=tracebacks, notes=notes)


BOOM_DOMAIN = """(define (domain boom) (:requirements :strips)
  (:predicates (p ?a) (q ?a ?b ?c ?d ?e) (done))
  (:action big :parameters (?a ?b ?c ?d ?e)
    :precondition (and (p ?a) (p ?b) (p ?c) (p ?d) (p ?e))
    :effect (and (q ?a ?b ?c ?d ?e) (done))))
"""
ALIAS_BOMB = "a: &a ['lol','lol','lol','lol','lol','lol','lol','lol','lol']\n" + "".join(
    f"{c}: &{c} [{','.join(['*' + p] * 9)}]\n" for p, c in zip("abcdefgh", "bcdefghi", strict=True)
)
HOSTILE_TIMEOUT_S = 240.0


@dataclass(frozen=True)
class Hostile:
    """One probe: the command, the exit code it must give, and the words its one
    ``error:`` line must hold (None: a success)."""

    name: str
    command: list[str]
    out: Path
    expected_exit: int
    words: tuple[str, ...] | None


def boom_data(root: Path, objects: int = 40) -> Path:
    folder = root / "x"
    folder.mkdir(parents=True)
    (folder / "domain.pddl").write_text(BOOM_DOMAIN)
    names = " ".join(f"o{i}" for i in range(objects))
    facts = " ".join(f"(p o{i})" for i in range(objects))
    (folder / "p01.pddl").write_text(
        f"(define (problem b1) (:domain boom) (:objects {names}) (:init {facts}) (:goal (done)))"
    )
    return root


def boom_command(data: Path, out: Path, *extra: str) -> list[str]:
    return [str(TWOSTEP), f"data.root={data}", "domain.name=x", "domain.agent_predicates=[p]",
            "task=1", "method=sa", f"output.root={out}", "mlflow.enabled=false",
            "orchestration.prefect=false", *extra]  # fmt: skip


def hostile_cases(root: Path) -> list[Hostile]:
    """Set up every probe under ``root``."""
    cases: list[Hostile] = []

    def data(tag: str, domain: str = "blocksworld") -> Path:
        folder = root / tag / "data"
        shutil.copytree(DATA / domain, folder / domain)
        return folder

    def twostep(tag: str, root_: Path, *extra: str) -> list[str]:
        return [str(TWOSTEP), "task=1", f"data.root={root_}", f"output.root={root / tag / 'out'}",
                "mlflow.enabled=false", "orchestration.prefect=false", *extra]  # fmt: skip

    def fifo(path: Path) -> None:
        path.unlink(missing_ok=True)
        os.mkfifo(path)

    def zero(path: Path) -> None:
        path.unlink(missing_ok=True)
        path.symlink_to("/dev/zero")

    def loop(path: Path) -> None:
        path.unlink(missing_ok=True)
        path.symlink_to(path.name)

    spoilers = {"fifo": (fifo, "FIFO"), "dev-zero": (zero, "character device"),
                "loop": (loop, "symlink loop")}  # fmt: skip
    for file in ("domain.pddl", "p01.pddl", "expert.yaml"):
        for kind, (spoil, words) in spoilers.items():
            tag = f"{file}-{kind}"
            folder = data(tag)
            spoil(folder / "blocksworld" / file)
            extra = ["method=twostep", "decomposer=expert"] if file == "expert.yaml" else []
            cases.append(Hostile(tag, twostep(tag, folder, *extra), root / tag / "out", 2,
                                 (str(folder / "blocksworld" / file), words)))  # fmt: skip
    for kind, script_text in (("fifo", None), ("alias-bomb", ALIAS_BOMB + "answers: [*i]\n")):
        tag = f"llm-script-{kind}"
        folder = data(tag)
        script = root / tag / "answers.yaml"
        if script_text is None:
            fifo(script)
        else:
            script.write_text(script_text)
        words = "FIFO" if script_text is None else "aliases expand"
        command = twostep(tag, folder, "decomposer=llm", "llm=scripted", f"llm.script={script}")
        cases.append(Hostile(tag, command, root / tag / "out", 2, (str(script), words)))
    kitchens = {
        "kitchen-huge": ("width: 13\nheight: 11", "width: 100000\nheight: 100000", "must be 1 to"),
        "kitchen-negative": ("diningtable1: [5, 5, 3, 2]", "diningtable1: [5, 5, -3, -2]",
                             "out of range"),
        "kitchen-not-a-number": ("loc-door: [6, 9]", 'loc-door: [6.5, "x"]', "of integers"),
        "kitchen-binary": (None, None, "not a text file"),
        "kitchen-fifo": (None, None, "FIFO"),
    }  # fmt: skip
    for tag, (old, new, words) in kitchens.items():
        folder = data(tag, "alfworld")
        kitchen = folder / "alfworld" / "kitchen.yaml"
        if old is not None and new is not None:
            kitchen.write_text(kitchen.read_text().replace(old, new, 1))
        elif tag == "kitchen-binary":
            bad_files.binary(kitchen)
        else:
            fifo(kitchen)
        command = twostep(tag, folder, "domain=alfworld", "task=4", "method=sa",
                          "executor=embodied", "executor.render=false")  # fmt: skip
        cases.append(Hostile(tag, command, root / tag / "out", 2, (str(kitchen), words)))
    tag = "unknown-scene"
    folder = data(tag, "alfworld")
    command = twostep(tag, folder, "domain=alfworld", "task=4", "method=sa", "executor=embodied",
                      "executor.render=false", "executor.layout=FloorPlan99999")  # fmt: skip
    cases.append(Hostile(tag, command, root / tag / "out", 2,
                         ("executor.layout=FloorPlan99999", "no layout")))  # fmt: skip
    tag = "type-typo"
    folder = data(tag)
    domain = folder / "blocksworld" / "domain.pddl"
    text = domain.read_text()
    typo = text.replace("(:predicates", "(:predicates (spare ?b - blok)", 1)
    domain.write_text(typo)
    cases.append(Hostile(tag, twostep(tag, folder), root / tag / "out", 2,
                         (str(domain), "type 'blok' is not declared")))  # fmt: skip
    for tag, extra, words in (
        ("boom-memory", ["planner.memory_limit_mb=300"], "planner.memory_limit_mb"),
        ("boom-time", ["planner.grounding_time_limit_s=5", "planner.memory_limit_mb=3000"],
         "planner.grounding_time_limit_s"),
    ):  # fmt: skip
        folder = boom_data(root / tag / "data")
        command = boom_command(folder, root / tag / "out", *extra)
        cases.append(Hostile(tag, command, root / tag / "out", 1, (words,)))
    tag = "agents-1000"
    cases.append(Hostile(tag, twostep(tag, DATA, "agents=1000"), root / tag / "out", 0, None))
    # issue 39, round four: an output root an MLflow address cannot hold, a key pasted into
    # the model's name, an executor value out of range (each: one line, exit 2, no folder)
    tag = "output-root-question-mark"
    out = root / tag / "q?mode=ro" / "out"
    command = [str(TWOSTEP), "task=1", f"data.root={DATA}", f"output.root='{out}'",
               "orchestration.prefect=false"]  # fmt: skip
    cases.append(Hostile(tag, command, out, 2, (f"output.root {out} holds '?'",)))
    tag = "key-in-llm-model"
    key = "sk-" + "probe" + "0123456789abcdef"  # a key's shape only
    command = twostep(tag, DATA, "decomposer=llm", "llm=gpt-4o", f"llm.model=openai/{key}")
    cases.append(Hostile(tag, command, root / tag / "out", 2, ("llm.model looks like",)))
    tag = "executor-stall-limit-0"
    command = twostep(tag, DATA, "domain=alfworld", "task=4", "executor.stall_limit=0")
    cases.append(Hostile(tag, command, root / tag / "out", 2,
                         ("executor.stall_limit=0 must be at least 1",)))  # fmt: skip
    return cases


MEASURED = """
import json, resource, subprocess, sys
try:
    done = subprocess.run(sys.argv[2:], capture_output=True, text=True, timeout=float(sys.argv[1]))
    code, out, err = done.returncode, done.stdout, done.stderr
except subprocess.TimeoutExpired as expired:
    code, out, err = None, str(expired.stdout or ""), str(expired.stderr or "")
print(json.dumps({"code": code, "stdout": out, "stderr": err,
                  "max_rss_kb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss}))
"""


def run_measured(command: list[str], timeout_s: float) -> dict[str, Any]:
    """``command``'s outcome (code None: stopped by the timeout) and the largest resident
    set of any process it ran, from a fresh process that only waits for it."""
    done = run([sys.executable, "-c", MEASURED, str(timeout_s), *command])
    return dict(json.loads(done.stdout))


def hostile_row(root: Path, args: argparse.Namespace) -> Row:
    cases = hostile_cases(root)
    answered = tracebacks = hangs = stored = 0
    notes: list[str] = []
    for case in cases:
        began = time.perf_counter()
        outcome = run_measured(case.command, HOSTILE_TIMEOUT_S)
        seconds = time.perf_counter() - began
        output = f"{outcome['stdout']}{outcome['stderr']}"
        tracebacks += output.count("Traceback")
        hangs += outcome["code"] is None
        errors = [line for line in str(outcome["stderr"]).splitlines() if line.startswith("error:")]
        wrong = [json.loads(p.read_text()) for p in case.out.glob("jobs/*/result.json")]
        stored += (
            sum(1 for r in wrong if not r.get("success")) if case.words is None else len(wrong)
        )
        if case.words is None:
            ok = outcome["code"] == case.expected_exit
        else:
            ok = (outcome["code"] == case.expected_exit and len(errors) == 1
                  and all(w in errors[0] for w in case.words))  # fmt: skip
        answered += ok
        memory = int(outcome["max_rss_kb"]) // 1024
        notes.append(f"hostile-inputs: {case.name}: exit {outcome['code']}, {seconds:.1f} s, "
                     f"max RSS {memory} MB{'' if ok else ': ' + (errors or [output.strip()[-160:]])[0][:200]}")  # fmt: skip
    row = Row("hostile-inputs", len(cases), answered, tracebacks=tracebacks, notes=notes)
    row.stored_failures = stored
    row.notes.insert(0, f"hostile-inputs: {hangs} hang(s) stopped at {HOSTILE_TIMEOUT_S:.0f} s; "
                        f"{stored} wrong job-store entries")  # fmt: skip
    return row


def orphans_row(root: Path, args: argparse.Namespace) -> Row:
    """Kill a job while it grounds ``boom``; count what it leaves."""
    kills = [("SIGKILL", signal.SIGKILL), ("SIGTERM", signal.SIGTERM), ("SIGINT", signal.SIGINT)]
    clean, notes = 0, []
    for name, signum in kills:
        tmp = root / name / "tmp"
        tmp.mkdir(parents=True)
        data = boom_data(root / name / "data")
        command = boom_command(data, root / name / "out", "planner.memory_limit_mb=1500")
        job = subprocess.Popen(command, env=dict(os.environ, TMPDIR=str(tmp)),
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               preexec_fn=_default_sigint)  # fmt: skip
        below: list[int] = []
        try:
            end = time.monotonic() + 120
            while time.monotonic() < end and not any(
                "fast_downward.translate" in _cmdline(p) for p in _descendants(job.pid)
            ):
                time.sleep(0.1)
            time.sleep(2.0)
            below = _descendants(job.pid)
            job.send_signal(signum)
            job.wait(timeout=60)
            time.sleep(5.0)
        finally:
            if job.poll() is None:
                job.kill()
                job.wait()
        left = [p for p in below if _running(p)]
        folders = list(tmp.glob("twostep-translate-*"))
        clean += not left and not folders and bool(below)
        notes.append(f"orphans: {name} during grounding: {len(below)} processes below the job, "
                     f"{len(left)} still running 5 s later, {len(folders)} temp folder(s) left")  # fmt: skip
        for pid in left:  # ours: stopped by PID
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
    return Row("orphans", len(kills), clean, notes=notes)


def _default_sigint() -> None:  # in the job before it starts: a background shell ignores ^C
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _descendants(pid: int) -> list[int]:
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            with contextlib.suppress(OSError, IndexError):
                parent = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
                children.setdefault(parent, []).append(int(entry.name))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return ""


def _running(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


SCENARIOS: dict[str, Callable[[Path, argparse.Namespace], Row]] = {
    "llm-faults": llm_faults,
    "deleted-store": deleted_store,
    "truncated-store": truncated_store,
    "concurrent": concurrent,
    "concurrent+svc": concurrent_services,
    "bad-files": bad_files_row,
    "hostile-inputs": hostile_row,
    "orphans": orphans_row,
}


def table(rows: list[Row]) -> list[str]:
    def cell(value: int | None) -> str:
        return "-" if value is None else str(value)

    values = [
        [r.scenario, *map(cell, (r.jobs, r.completed, r.recomputed, r.runs, r.duplicates,
                                 r.missing, r.stored_failures, r.tracebacks))]
        for r in rows
    ]  # fmt: skip
    header = ["scenario", *COLUMNS]
    widths = [max(len(row[i]) for row in [header, *values]) for i in range(len(header))]
    lines = ["  ".join(text.ljust(w) if i == 0 else text.rjust(w) for i, (text, w) in
                       enumerate(zip(row, widths, strict=True))) for row in [header, *values]]  # fmt: skip
    return [lines[0], "-" * len(lines[0]), *lines[1:]]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default=",".join(SCENARIOS), help="comma-separated scenarios")
    parser.add_argument("--jobs", type=int, default=20, help="llm-faults: jobs")
    parser.add_argument("--kills", type=int, default=2, help="llm-faults: SIGKILLs")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--fault-rate", type=float, default=0.15, help="per fault kind")
    parser.add_argument("--save", type=Path, default=None, help="also write the table here")
    parser.add_argument("--json", type=Path, help="also write the rows here (a bench record)")
    args = parser.parse_args()
    run = bench_record.started()
    chosen = [name.strip() for name in args.only.split(",") if name.strip()]
    unknown = [name for name in chosen if name not in SCENARIOS]
    if unknown:
        parser.error(f"unknown scenario(s) {', '.join(unknown)}; known: {', '.join(SCENARIOS)}")
    base = Path(tempfile.mkdtemp(prefix="bench-faults-"))
    rows, start = [], time.perf_counter()
    for name in chosen:
        began = time.perf_counter()
        row = SCENARIOS[name](base / name.replace("+", "-"), args)
        row.notes.append(f"{name}: {time.perf_counter() - began:.0f} s")
        rows.append(row)
    lines = table(rows) + [""] + [note for row in rows for note in row.notes]
    lines.append(f"total {time.perf_counter() - start:.0f} s, seed {args.seed}, outputs in {base}")
    text = "\n".join(lines)
    print(text)
    if args.save:
        args.save.write_text(text + "\n")
    if args.json:  # docs/bench/faults.json: the results page's rows (make results)
        settings = {"jobs": args.jobs, "kills": args.kills, "seed": args.seed,
                    "fault_rate": args.fault_rate}  # fmt: skip
        bench_record.write(args.json, run, [asdict(r) for r in rows], settings=settings,
                           seconds=time.perf_counter() - start)  # fmt: skip


if __name__ == "__main__":
    main()
