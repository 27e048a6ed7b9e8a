"""What the commands print: a job's summary line and schedule table, a sweep's progress
line, header and footer, any error on one line, and ``twostep --version``."""

from __future__ import annotations

import logging
import math
import platform
import re
import subprocess
import time
from collections.abc import Mapping
from importlib import metadata, util
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flows.identity import job_name
from flows.status import reason_line
from twostep.util.outcome import EmbodiedStatus, JobStatus, RunStatus, SubgoalStatus, limit_reached
from twostep.util.redaction import redact_text

if TYPE_CHECKING:
    from flows.sweep_state import SweepState
    from twostep.methods import RunResult


def one_line(error: BaseException, name_type: bool = True, limit: int | None = None) -> str:
    """The error's first non-empty line, after its type's name unless ``name_type`` is
    False (errors whose message is written for the user), cut at ``limit`` characters;
    credentials inside URLs masked (:mod:`twostep.util.redaction`)."""
    lines = [line for line in redact_text(str(error)).strip().splitlines() if line.strip()]
    # SQLAlchemy's preamble ("(raised as a result of Query-invoked autoflush; ...)"):
    # the line after it says what went wrong (database or disk is full).
    lines = [line for line in lines if not line.startswith("(raised as a result of")] or lines
    text = lines[0] if lines else ""
    if not name_type:
        text = text or type(error).__name__
    else:
        text = f"{type(error).__name__}: {text}" if text else type(error).__name__
    return text if limit is None else text[:limit]


class MaskCredentials(logging.Filter):
    """A logging filter (conf/hydra/*_logging/twostep.yaml): every record's text with the
    credentials inside its URLs masked, e.g. Hydra's line of a job's overrides."""

    def filter(self, record: logging.LogRecord) -> bool:
        text = record.getMessage()
        masked = redact_text(text)
        if masked != text:
            record.msg, record.args = masked, ()
        return True


# ----------------------------------------------------------------- one job


def format_summary(result: RunResult | Mapping[str, Any], name: str | None = None) -> str:
    """One line for the terminal (from a result or its result.json dict), starting with
    the job's name (``name``, else made from the result: :func:`flows.identity.job_name`)."""
    r = result if isinstance(result, Mapping) else result.to_dict()
    name = name or job_name(r)
    if r.get("status") == RunStatus.FAILED and "error" in r:
        return redact_text(f"{name} | FAILED: {r['error']}")
    status, message = str(r.get("status")), str(r.get("message") or "")
    if r.get("success"):
        outcome = "success"
    elif limit_reached(status):  # a timeout is not a failure of the job: it is counted apart
        outcome = f"TIMED OUT ({message or 'planner time limit'})"
    else:
        outcome = f"FAILED ({reason_line(status, message)})"
    parts = [
        name,
        outcome,
        f"exec_length={r.get('exec_length')}",
    ]
    if r.get("sa_length") is not None:
        parts.append(f"sa_length={r['sa_length']}")
    parts.append(f"planning_time={float(r.get('planning_time_s') or 0.0):.2f}s")
    subgoals = r.get("subgoals") or []
    chosen = [d for d in r.get("deal") or [] if d.get("chosen")]
    if chosen:  # plan-deal: pieces, not subgoals
        d = chosen[0]
        parts.append(f"dealt {d.get('pieces')} pieces ({d.get('walks')} walking steps)")
    elif r.get("decomposer"):
        accepted = sum(1 for s in subgoals if s.get("status") == SubgoalStatus.ACCEPTED)
        parts.append(f"subgoals={accepted}/{len(subgoals)} accepted")
    if r.get("fallback"):
        parts.append(f"fallback: {r['fallback']}")
    if r.get("executor") == "embodied":
        embodied = r.get("embodied") or {}
        if r.get("embodied_status") == EmbodiedStatus.SUCCESS:
            parts.append(
                f"embodied_length={r.get('embodied_length')} "
                f"(waits={r.get('waits')}, backoffs={r.get('backoffs')})"
            )
        else:
            where = f" {embodied.get('agent')} at step {embodied.get('step')}"
            where = where if embodied.get("agent") is not None else ""
            parts.append(
                f"embodied: {r.get('embodied_status')}{where}: {embodied.get('reason', '')}"
            )
    return redact_text(" | ".join(parts))


def _agent_number(agent: str) -> int:
    digits = agent.removeprefix("agent")
    return int(digits) if digits.isdigit() else 0


def format_schedule(result: RunResult | Mapping[str, Any]) -> str:
    """The joint schedule as a table, one column per agent, each as wide as its longest
    action (two spaces apart)."""
    r = result if isinstance(result, Mapping) else result.to_dict()
    agents = sorted(r.get("plans") or {}, key=_agent_number)
    schedule = r.get("schedule") or []
    if not schedule or len(agents) < 2:
        return ""
    widths = {agent: len(agent) for agent in agents}
    for step in schedule:
        for agent, action in step:
            widths[agent] = max(widths.get(agent, 0), len(action))

    def row(first: str, cells: Mapping[str, str]) -> str:
        columns = [cells.get(a, ".").ljust(widths[a]) for a in agents]
        return (first + "  " + "  ".join(columns)).rstrip()

    header = row("step", {a: a for a in agents})
    lines = [header, "-" * (4 + 2 + sum(widths.values()) + 2 * (len(agents) - 1))]
    for t, step in enumerate(schedule, start=1):
        lines.append(row(f"{t:>4}", {agent: action for agent, action in step}))
    return "\n".join(lines)


# ----------------------------------------------------------------- a sweep


def clock(seconds: float) -> str:
    seconds = max(0, round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


def eta_seconds(state: SweepState, records: list[dict[str, Any]], elapsed: float) -> float | None:
    """Seconds left: the finished jobs' mean time (without waiting for the server) times
    the jobs left, over the jobs that run at once (``state.parallel``: the launcher's);
    throughput so far when that is unknown. None before any job finished."""
    total, done = state.total_jobs, len(records)
    if total is None or not 0 < done < total:
        return None
    timed = [r for r in records if isinstance(r.get("job_wall_time_s"), int | float)]
    # A worker's first job also paid its process's one-time start (the first flow run's
    # client set-up, the first MLflow client): left out once a later job has finished.
    later = [r for r in timed if (r.get("launch") or {}).get("worker_job") != 0]
    times = [
        float(r["job_wall_time_s"]) - float(r.get("server_wait_s") or 0.0) for r in later or timed
    ]
    left = total - done
    if not times or not state.parallel:
        return elapsed / done * left
    return sum(times) / len(times) * math.ceil(left / state.parallel)


def outcome_counts(records: list[dict[str, Any]]) -> str:
    """``3 ok, 1 failed, 1 timed out``: how the finished jobs ended (the three add up to
    the jobs finished)."""
    statuses = [r.get("status") for r in records]
    ok = statuses.count(JobStatus.SUCCESS)
    timed_out = statuses.count(JobStatus.TIMEOUT)
    return f"{ok} ok, {len(records) - ok - timed_out} failed, {timed_out} timed out"


def progress_line(state: SweepState, now: float | None = None) -> str:
    """``[5/8: 3 ok, 1 failed, 1 timed out | 1 reused | 0:41 elapsed, ~0:14 left]``
    (``now``: the time to measure from, default the clock's)."""
    from flows.sweep_state import job_records

    records = job_records(Path(state.sweep_dir))
    done = len(records)
    reused = sum(1 for r in records if r.get("reused"))
    elapsed = (time.time() if now is None else now) - state.started_at
    total = state.total_jobs
    parts = [f"{done}/{total if total is not None else '?'}: {outcome_counts(records)}"]
    if reused:
        parts.append(f"{reused} reused")
    timing = f"{clock(elapsed)} elapsed"
    eta = eta_seconds(state, records, elapsed)
    if eta is not None:
        timing += f", ~{clock(eta)} left"
    parts.append(timing)
    return "[" + " | ".join(parts) + "]"


def header(state: SweepState) -> str:
    total = state.total_jobs if state.total_jobs is not None else "?"
    parts = [f"sweep: {total} jobs -> {state.sweep_dir}"]
    if state.prefect_api_url:
        parts.append(f"prefect {state.prefect_api_url}")
    elif state.server:
        parts.append("prefect server on demand")
    if state.experiment:
        parts.append(f"mlflow experiment '{state.experiment}'")
    if state.dask_address:
        parts.append(f"dask {state.dask_address}")
    return redact_text(" | ".join(parts))


def footer(state: SweepState, summary: Mapping[str, Any], failed: list[dict[str, Any]]) -> str:
    ok = summary["jobs_done"] - summary["jobs_failed"] - summary["jobs_timeout"]
    lines = [
        f"sweep finished: {summary['jobs_done']}/{summary['jobs_total']} jobs: {ok} ok, "
        f"{summary['jobs_failed']} failed, {summary['jobs_timeout']} timed out | "
        f"{summary['jobs_reused']} reused | planner calls: {summary['planner_calls_run']} run, "
        f"{summary['plan_cache_hits']} from cache | {clock(summary['sweep_wall_time_s'])}"
    ]
    refused, unstored = summary.get("jobs_store_refused", 0), summary.get("jobs_not_stored", 0)
    if refused:
        lines.append(
            f"job store: {refused} stored entr{'y' if refused == 1 else 'ies'} not this "
            "job's or not whole: computed again (warnings above)"
        )
    faults = summary.get("jobs_fault", 0)
    if faults:
        lines.append(
            f"{faults} job(s) could not write their run directory (a full disk or a "
            "read-only folder: see their lines); a re-run computes them"
        )
    if unstored:
        lines.append(
            f"job store: {unstored} job(s) could not be stored (their run directories keep "
            "their results; a re-run computes them again)"
        )
    for record in failed[:10]:
        lines.append(f"  failed: {record.get('name')}: {record.get('error')}")
    runs = summary.get("prefect_flow_runs")
    if runs is not None:
        shown = ", ".join(f"{n} {s.lower()}" for s, n in sorted(runs.items())) or "none"
        stopped = " (server stopped)" if summary.get("prefect_server_started") else ""
        lines.append(f"prefect: {summary['prefect_api_url']}: flow runs: {shown}{stopped}")
    if state.experiment:
        lines.append(f"mlflow: experiment '{state.experiment}' in {state.tracking_uri}")
    return redact_text("\n".join(lines))


# ----------------------------------------------------------------- versions


def _distribution_version(name: str) -> str:
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return "not installed"


def fast_downward_version() -> str:
    """The release of the Fast Downward inside the up-fast-downward wheel, read from its
    driver's version file (nothing is imported)."""
    spec = util.find_spec("up_fast_downward")
    folders = list(spec.submodule_search_locations or []) if spec else []
    for folder in folders:
        path = Path(folder) / "downward" / "driver" / "version.py"
        found = (
            re.search(r"__version__\s*=\s*[\"']([^\"']+)", path.read_text())
            if path.is_file()
            else None
        )
        if found:
            return found.group(1)
    return "unknown"


SOURCE_ROOT = Path(__file__).resolve().parent.parent  # a checkout's top, or site-packages


def git_state(source: Path = SOURCE_ROOT) -> tuple[str, bool] | None:
    """(full commit, whether tracked files have uncommitted changes) of the checkout this
    code runs from; None for an installed wheel (no checkout around the package)."""

    def git(*args: str) -> str | None:
        try:
            done = subprocess.run(
                ["git", "-C", str(source), *args], capture_output=True, text=True, timeout=10
            )
        except (OSError, subprocess.SubprocessError):
            return None
        return done.stdout.strip() if done.returncode == 0 else None

    top = git("rev-parse", "--show-toplevel")
    if top is None or Path(top).resolve() != source:
        return None  # not a checkout of this project (e.g. a venv inside another repository)
    commit = git("rev-parse", "HEAD")
    if commit is None:
        return None
    return commit, bool(git("status", "--porcelain", "--untracked-files=no"))


def git_commit(source: Path = SOURCE_ROOT) -> str | None:
    """The short commit of the checkout this code runs from (``+ changes`` when the tree
    has uncommitted changes); None for an installed wheel."""
    state = git_state(source)
    if state is None:
        return None
    commit, dirty = state[0][:12], state[1]
    return f"{commit} + changes" if dirty else commit


def version_text() -> str:
    """``twostep --version``: twostep's version and commit, and what it runs on (versions
    from the installed metadata: nothing heavy is imported)."""
    commit = git_commit()
    lines = [
        f"twostep {_distribution_version('twostep')}"
        + (f" (git {commit})" if commit else " (installed package, no git checkout)"),
        f"Python {platform.python_version()} on {platform.system()} {platform.machine()}",
        f"Fast Downward {fast_downward_version()} "
        f"(up-fast-downward {_distribution_version('up-fast-downward')})",
    ]
    for label, name in (
        ("unified-planning", "unified-planning"),
        ("Hydra", "hydra-core"),
        ("Prefect", "prefect"),
        ("MLflow", "mlflow"),
        ("litellm", "litellm"),
    ):
        lines.append(f"{label} {_distribution_version(name)}")
    return "\n".join(lines)
