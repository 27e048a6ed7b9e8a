"""Bounded grounding and planning (issue 39, finding 1): Fast Downward's translator and
planner run under a memory limit and (grounding) a CPU-time limit, and nothing of them
outlives the job.

Before: a 5-ary action over 40 objects (``boom``) grew to 6 GB in 218 s with nothing
printed (no memory limit on grounding, only a 300 s wall timeout); ``kill -9`` of the job
left the translator running under PID 1 (5.5 GB 100 s later) and a ``twostep-translate-*``
folder behind; ``planner.memory_limit_mb=1`` failed as "unexpected exit code 127".

The limits here are set low so that each test takes seconds; the probe's task is the
same. Memory is measured apart from the code under test: the largest resident set of
any process the command ran (``getrusage(RUSAGE_CHILDREN)`` of a fresh process that only
waits for it).
"""

from __future__ import annotations

import json
import os
import pickle
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from flows.build import keyed_plan_result
from flows.identity import job_key
from tests.conftest import DATA
from twostep.pddl import load_problem
from twostep.pddl.translator import GroundingLimits
from twostep.planner import PlannerSettings, plan_pddl
from twostep.programs.processes import Limit, ResourceLimitError

BIN = Path(sys.executable).parent
BOOM_DOMAIN = """(define (domain boom) (:requirements :strips)
  (:predicates (p ?a) (q ?a ?b ?c ?d ?e) (done))
  (:action big :parameters (?a ?b ?c ?d ?e)
    :precondition (and (p ?a) (p ?b) (p ?c) (p ?d) (p ?e))
    :effect (and (q ?a ?b ?c ?d ?e) (done))))
"""


def boom_problem(objects: int) -> str:
    names = " ".join(f"o{i}" for i in range(objects))
    facts = " ".join(f"(p o{i})" for i in range(objects))
    return f"(define (problem b1) (:domain boom) (:objects {names}) (:init {facts}) (:goal (done)))"


@pytest.fixture
def boom(tmp_path: Path) -> Path:
    """A data root with ``x``: the probe's boom task over 40 objects (10^8 ground actions)."""
    folder = tmp_path / "data" / "x"
    folder.mkdir(parents=True)
    (folder / "domain.pddl").write_text(BOOM_DOMAIN)
    (folder / "p01.pddl").write_text(boom_problem(40))
    return tmp_path / "data"


def boom_command(data: Path, out: Path, *extra: str) -> list[str]:
    return [
        str(BIN / "twostep"), f"data.root={data}", "domain.name=x", "domain.agent_predicates=[p]",
        "task=1", "method=sa", f"output.root={out}", "mlflow.enabled=false",
        "orchestration.prefect=false", *extra,
    ]  # fmt: skip


MEASURED = """
import json, resource, subprocess, sys
done = subprocess.run(sys.argv[1:], capture_output=True, text=True, timeout=600)
print(json.dumps({"code": done.returncode, "stdout": done.stdout, "stderr": done.stderr,
                  "max_rss_kb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss}))
"""


def measured(command: list[str], env: dict[str, str] | None = None) -> dict[str, object]:
    """Run ``command`` from a fresh process; its outcome and the largest resident set (KB)
    of any process it ran."""
    done = subprocess.run(
        [sys.executable, "-c", MEASURED, *command], capture_output=True, text=True, env=env,
        timeout=700,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return dict(json.loads(done.stdout))


def limit_failure(outcome: dict[str, object], key: str, out: Path) -> str:
    """The run failed on a limit: exit 1, no traceback, one ``error:`` line naming the
    limit's key; result.json says ``resource_limit``; the job store holds nothing."""
    output = f"{outcome['stdout']}{outcome['stderr']}"
    assert "Traceback" not in output, output[-3000:]
    assert outcome["code"] == 1, output[-3000:]
    errors = [line for line in str(outcome["stderr"]).splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and key in errors[0], output[-3000:]
    (result,) = out.glob("runs/*/*/result.json")
    stored = json.loads(result.read_text())
    assert stored["status"] == "resource_limit" and stored["success"] is False
    assert "unsolvable" not in stored["message"]
    assert not list((out / "jobs").glob("*/result.json"))
    return errors[0]


def test_the_explosive_grounding_stops_at_the_memory_limit(boom: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    # 200 MB is reached in about 2 s of CPU; the CPU limit (600 s) cannot come first, however
    # loaded the machine (at 300 MB and 60 s it sometimes did).
    limit_mb = 200
    outcome = measured(
        boom_command(
            boom, out, f"planner.memory_limit_mb={limit_mb}", "planner.grounding_time_limit_s=600"
        )
    )
    line = limit_failure(outcome, "planner.memory_limit_mb", out)
    # What the job prints and stores names the config key, word for word as before the
    # library's limits named their own parameters (the message written out by hand).
    files = f"{boom / 'x' / 'p01.pddl'} (domain {boom / 'x' / 'domain.pddl'})"
    said = (
        f"{files}: grounding ran out of memory: Fast Downward's translator needs more than "
        "the 200 MB of planner.memory_limit_mb (raise it, e.g. planner.memory_limit_mb=400)"
    )
    assert line == f"error: {said}"
    (result,) = out.glob("runs/*/*/result.json")
    stored = json.loads(result.read_text())
    assert (stored["message"], stored["error"]) == (said, said)
    assert int(str(outcome["max_rss_kb"])) <= limit_mb * 1024  # no process went over


def test_the_explosive_grounding_stops_at_the_time_limit(boom: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    outcome = measured(
        boom_command(boom, out, "planner.grounding_time_limit_s=2", "planner.memory_limit_mb=3000")
    )
    line = limit_failure(outcome, "planner.grounding_time_limit_s", out)
    assert "grounding" in line and "2 s of CPU time" in line  # (or the wall guard, loaded)


def test_grounding_limits_in_the_library(tmp_path: Path) -> None:
    """The library's error says which limit, its value and the library's own parameter.

    100 MB is reached in about a second of CPU; the CPU limit (600 s) cannot come first,
    however loaded the machine."""
    (tmp_path / "domain.pddl").write_text(BOOM_DOMAIN)
    (tmp_path / "p01.pddl").write_text(boom_problem(40))
    limits = GroundingLimits(100, time_s=600)
    with pytest.raises(ResourceLimitError) as caught:
        load_problem(tmp_path / "domain.pddl", tmp_path / "p01.pddl", limits=limits)
    files = f"{tmp_path / 'p01.pddl'} (domain {tmp_path / 'domain.pddl'})"
    assert str(caught.value) == (
        f"{files}: grounding ran out of memory: Fast Downward's translator needs more than "
        "the 100 MB of GroundingLimits.memory_mb (raise it, e.g. GroundingLimits.memory_mb=200)"
    )
    reached = caught.value.reached
    assert (reached.limit, reached.value, reached.parameter) == (
        Limit.MEMORY, 100, "GroundingLimits.memory_mb"
    )  # fmt: skip
    assert reached.message("memory") == str(caught.value).replace(
        "GroundingLimits.memory_mb", "memory"
    )
    again = pickle.loads(pickle.dumps(caught.value))  # whole across processes (Dask)
    assert (str(again), again.reached) == (str(caught.value), reached)
    (tmp_path / "p02.pddl").write_text(boom_problem(3))  # 243 ground actions: well within
    problem = load_problem(tmp_path / "domain.pddl", tmp_path / "p02.pddl", limits=limits)
    assert len(problem.grounded.actions) == 3**5


def test_limits_out_of_range_are_refused_before_work(tmp_path: Path) -> None:
    for override, words in [
        ("planner.memory_limit_mb=1", "planner.memory_limit_mb=1 must be at least 64"),
        ("planner.grounding_time_limit_s=0", "planner.grounding_time_limit_s=0.0 must be > 0"),
    ]:
        done = subprocess.run(
            [str(BIN / "twostep"), "task=1", override, f"output.root={tmp_path}/out",
             "mlflow.enabled=false", "orchestration.prefect=false"],
            capture_output=True, text=True, timeout=120,
        )  # fmt: skip
        assert done.returncode == 2 and words in done.stderr, done.stderr


def test_the_grounding_time_limit_leaves_job_keys_as_they_were() -> None:
    """A limit hit is never stored, so no stored result depends on the key: configs that
    differ only in it share their key, and one written before the key existed too."""
    base = {"domain": {"name": "blocksworld"}, "task": 1, "method": {"name": "sa"},
            "planner": {"alias": "lama-first", "time_limit_s": 60.0, "memory_limit_mb": None}}  # fmt: skip
    with_key = {**base, "planner": {**base["planner"], "grounding_time_limit_s": 5.0}}  # type: ignore[dict-item]
    assert job_key(base) == job_key(with_key)
    memory = {**base, "planner": {**base["planner"], "memory_limit_mb": 2048}}  # type: ignore[dict-item]
    assert job_key(base) != job_key(memory)  # a planner's memory limit can change a result


# ----------------------------------------------------------------- no orphans


def descendants(pid: int) -> list[int]:
    """Every process below ``pid`` (read from /proc)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            children.setdefault(int(fields[1]), []).append(int(entry.name))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def alive(pid: int) -> bool:
    """Running, not a zombie waiting for PID 1 to reap it."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def command_line(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return ""


def wait_for(pid: int, words: str, timeout: float = 120) -> list[int]:
    """The descendants of ``pid`` once one of them runs a command with ``words``."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        below = descendants(pid)
        if any(words in command_line(p) for p in below):
            time.sleep(1.0)  # well inside its work
            return descendants(pid)
        time.sleep(0.1)
    raise AssertionError(f"no '{words}' below {pid} after {timeout} s")


def none_left(pids: list[int], tmp: Path, prefix: str) -> None:
    """No process of ``pids`` still runs and no ``prefix*`` folder is left in ``tmp``."""
    end = time.monotonic() + 15
    while time.monotonic() < end and (any(map(alive, pids)) or list(tmp.glob(f"{prefix}*"))):
        time.sleep(0.1)
    assert not [p for p in pids if alive(p)], [command_line(p) for p in pids if alive(p)]
    assert not list(tmp.glob(f"{prefix}*"))


def default_sigint() -> None:  # runs in the job before it starts
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.parametrize("signum", [signal.SIGKILL, signal.SIGTERM, signal.SIGINT])
def test_killing_a_job_mid_translation_leaves_nothing(
    boom: Path, tmp_path: Path, signum: int
) -> None:
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = dict(os.environ, TMPDIR=str(tmp))
    command = boom_command(boom, tmp_path / "out", "planner.memory_limit_mb=1500")
    job = subprocess.Popen(
        command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        preexec_fn=default_sigint,  # a shell's background job ignores Ctrl-C: not the job
    )  # fmt: skip
    try:
        below = wait_for(job.pid, "fast_downward.translate")
        assert list(tmp.glob("twostep-translate-*"))
        job.send_signal(signum)
        job.wait(timeout=60)
        none_left(below, tmp, "twostep-translate-")
    finally:
        if job.poll() is None:
            job.kill()
            job.wait()


PLANNING = """
import sys
from pathlib import Path
from twostep.planner import PlannerSettings, plan_pddl
folder = Path(sys.argv[1])
plan_pddl((folder / "domain.pddl").read_text(), (folder / "p01.pddl").read_text(),
          PlannerSettings("astar-blind", 300))
"""


def test_killing_a_job_mid_search_leaves_nothing(tmp_path: Path) -> None:
    """The planner's driver, its translator and its search all end with the job (a blind
    search on a large blocksworld task runs for minutes)."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = dict(os.environ, TMPDIR=str(tmp))
    job = subprocess.Popen([sys.executable, "-c", PLANNING, str(DATA / "large" / "blocksworld")],
                           env=env)  # fmt: skip
    try:
        below = wait_for(job.pid, "bin/downward", timeout=240)  # the search binary
        assert list(tmp.glob("twostep-fd-*"))
        job.kill()
        job.wait(timeout=60)
        none_left(below, tmp, "twostep-fd-")
    finally:
        if job.poll() is None:
            job.kill()
            job.wait()


def test_the_planner_runs_under_the_memory_limit() -> None:
    """A tiny task plans under the smallest limit that can be set."""
    domain, problem = BOOM_DOMAIN, boom_problem(2)
    result = plan_pddl(domain, problem, PlannerSettings("lama-first", 10, None, 64))
    assert result.solved and len(result.plan or ()) == 1, result.message


def test_a_search_out_of_memory_names_the_limit() -> None:
    """Fast Downward's search ends itself at the limit (exit 22): an error, not a proof.
    The library names its own parameter; a job (``flows/``) names the config key, as it
    always has."""
    folder = DATA / "large" / "blocksworld"
    settings = PlannerSettings("astar-blind", 120, None, 100)  # blind search fills memory
    result = plan_pddl(
        (folder / "domain.pddl").read_text(), (folder / "p01.pddl").read_text(), settings
    )
    assert (result.status.value, result.exit_code) == ("error", 22)
    assert result.message == (
        "search out of memory (the 100 MB of PlannerSettings.memory_limit_mb: raise it)"
    )
    assert result.limit is not None and (result.limit.limit, result.limit.value) == (
        Limit.MEMORY, 100
    )  # fmt: skip
    assert (
        keyed_plan_result(result).message
        == "search out of memory (the 100 MB of planner.memory_limit_mb: raise it)"
    )
    assert result.to_dict() == {**keyed_plan_result(result).to_dict(), "message": result.message}


def test_a_job_whose_search_runs_out_of_memory_names_the_config_key(tmp_path: Path) -> None:
    """What a job stores of a planner call that reached the memory limit names the config
    key, word for word as before the library named its own parameter."""
    out = tmp_path / "out"
    done = subprocess.run(
        [str(BIN / "twostep"), f"data.root={DATA / 'large'}", "domain=blocksworld", "task=1",
         "method=sa", "planner.alias=astar-blind", "planner.memory_limit_mb=100",
         "compare_sa=false", f"output.root={out}", "mlflow.enabled=false",
         "orchestration.prefect=false"],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    said = "search out of memory (the 100 MB of planner.memory_limit_mb: raise it)"
    (result,) = out.glob("runs/*/*/result.json")
    stored = json.loads(result.read_text())
    assert (stored["status"], stored["message"]) == ("error", said), done.stderr[-2000:]
    assert [c["message"] for c in stored["planner_calls"]] == [said]
    assert f"(error: {said})" in done.stdout + done.stderr


def test_a_prefect_planner_crash_names_the_config_key() -> None:
    """The Prefect task's failure (a planner error is raised there, not cached) words the
    limit with the config key too."""
    from flows.prefect_flow import PlannerCrashed
    from twostep.planner import PlanResult, Status
    from twostep.programs.processes import LimitReached

    words = "search out of memory (the 100 MB of {parameter}: raise it)"
    limit = LimitReached(Limit.MEMORY, 100, None, words, "PlannerSettings.memory_limit_mb")
    result = PlanResult(Status.ERROR, None, 1.0, 1.0, limit.message(), 22, limit=limit)
    assert str(PlannerCrashed(result)) == (
        "planner error: search out of memory (the 100 MB of planner.memory_limit_mb: raise it)"
    )
