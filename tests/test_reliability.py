"""Regression tests for the reliability findings (issue 12, findings 3, 4 and 5): concurrent
sweeps, unwritable locations, bad config values, PDDL errors, and a fast kill -9 / resume;
and issue 20's finding 7 (values and messages). The other findings of issue 20 have their
own files: test_tracking_view (1, 2), test_llm_client (3, 7: HTTP 401), test_bad_files
(4, 7), test_secrets (5), test_prefect_states (6), test_packaging (8).

Every run goes through the ``twostep`` command as a user starts it, with Prefect off
(``orchestration.prefect=false``) and tiny blocksworld tasks, so each takes seconds.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from flows.checks import value_problems
from flows.locations import write_problem
from flows.store import JobStore
from flows.sweep_callback import _refuse_running_sweep
from flows.sweep_state import SweepState
from tests.support.commands import REPO, compose_config
from tests.support.data import make_data
from twostep.pddl import PDDLError, load_problem, parse_goal

TWOSTEP = Path(sys.executable).parent / "twostep"
FAST = ["orchestration.prefect=false", "planner.time_limit_s=20"]
# A made-up key, assembled here so that secret scanners do not take the repository for
# one that leaks a key (it is a key's shape only: no service knows it).
MADE_UP_KEY = "sk-" + "proj-" + "0123456789abcdef"


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make_data(tmp_path_factory.mktemp("reliability") / "data")


def twostep(*args: str, timeout: float = 240) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(TWOSTEP), *args], capture_output=True, text=True, cwd=REPO, timeout=timeout
    )


def one_error_line(done: subprocess.CompletedProcess[str]) -> str:
    """The single ``error:`` line of a run that failed on its input (and no traceback)."""
    assert done.returncode == 2, done.stdout + done.stderr
    assert "Traceback" not in done.stderr, done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1, done.stderr
    return errors[0]


# ----------------------------------------------------------------- finding 5: values


@pytest.mark.parametrize(
    ("override", "expected"),
    [
        ("score_mode=bogus", "score_mode=bogus is not allowed (allowed: exact, paper)"),
        ("planner.time_limit_s=0", "planner.time_limit_s=0.0 must be > 0"),
        ("planner.time_limit_s=-5", "planner.time_limit_s=-5.0 must be > 0"),
        (
            "llm.mode=sometimes",
            "llm.mode=sometimes is not allowed (allowed: live, replay, scripted, bundle)",
        ),
        ("llm.translator=regex", "llm.translator=regex is not allowed (allowed: llm, rules)"),
        ("agents=0", "agents=0 must be at least 1"),
        ("llm.timeout_s=0", "llm.timeout_s=0.0 must be > 0"),
        # issue 20, finding 7: before, `OverflowError: timeout is too large` (no key named)
        (
            "planner.time_limit_s=1e9",
            "planner.time_limit_s=1000000000.0 is too large (allowed: > 0 and at most 1000000 "
            "seconds)",
        ),
        (
            "score_time_limit_s=inf",
            "score_time_limit_s=inf is too large (allowed: > 0 and at most 1000000 seconds)",
        ),
        (
            "llm.api_key_env=" + MADE_UP_KEY,
            "llm.api_key_env looks like a key, not a variable name: give the name of the "
            "environment variable that holds the key (e.g. llm.api_key_env=OPENAI_API_KEY); "
            "the value is not shown",
        ),
    ],
)
def test_each_bad_value_is_named_with_what_is_allowed(override: str, expected: str) -> None:
    assert value_problems(compose_config(override)) == [expected]


def test_default_config_has_no_bad_value() -> None:
    assert value_problems(compose_config()) == []


def test_bad_score_mode_fails_before_planning_and_stores_nothing(
    data: Path, tmp_path: Path
) -> None:
    """Before: with sa (no scoring needed) score_mode=bogus was stored as a success."""
    out = tmp_path / "out"
    done = twostep(
        "method=sa", "task=1", "score_mode=bogus", "mlflow.enabled=false",
        f"data.root={data}", f"output.root={out}", *FAST,
    )  # fmt: skip
    assert "score_mode=bogus" in one_error_line(done) and "exact, paper" in done.stderr
    # refused before Hydra made the run's folder (issue 37): nothing written at all
    assert not out.exists()


# ----------------------------------------------------------------- finding 4: writing


def test_unwritable_output_root_is_one_line_before_any_work(data: Path, tmp_path: Path) -> None:
    """Before: Hydra's traceback (creating the run dir). A path under a regular file is
    unwritable for every user, root included (permission bits are not, for root)."""
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    for mode in ([], ["-m"]):
        done = twostep(*mode, "task=1", f"data.root={data}", f"output.root={blocker}/out", *FAST)
        assert f"output.root {blocker}/out is not writable" in one_error_line(done)


def test_unwritable_job_store_is_refused_before_the_job_computes(
    data: Path, tmp_path: Path
) -> None:
    """Before: the job computed, then died writing the store, leaving no result.json."""
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    out = tmp_path / "out"
    done = twostep(
        "task=1", "mlflow.enabled=false", f"orchestration.job_store={blocker}/jobs",
        f"data.root={data}", f"output.root={out}", *FAST,
    )  # fmt: skip
    assert "orchestration.job_store" in one_error_line(done)
    assert not list(out.glob("runs/*/*/result.json"))  # refused: nothing computed


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes through permission bits")
def test_read_only_folder_is_reported(tmp_path: Path) -> None:
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        assert write_problem(folder / "out") is not None
    finally:
        folder.chmod(0o755)


def test_job_store_failing_after_the_work_keeps_the_result(
    data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The store becomes unwritable while the job runs: result.json is still written to
    the run directory, and a warning says where it is."""
    from hydra import compose, initialize_config_dir

    from flows.config import register
    from flows.job import execute_job

    blocker = tmp_path / "a-file"
    blocker.write_text("")
    register()
    with initialize_config_dir(config_dir=str(REPO / "conf"), version_base="1.3"):
        cfg = compose(
            "config",
            overrides=[
                "task=1", "mlflow.enabled=false", f"orchestration.job_store={blocker}/jobs",
                f"data.root={data}", f"output.root={tmp_path / 'out'}", *FAST,
            ],
        )  # fmt: skip
    job_dir = tmp_path / "job"
    outcome = execute_job(cfg, job_dir)
    assert outcome.status == "success"
    assert json.loads((job_dir / "result.json").read_text())["success"] is True
    warning = capsys.readouterr().err
    assert f"job store {blocker}/jobs not written" in warning and "result.json" in warning


# ----------------------------------------------------------------- finding 3: concurrency


def test_second_claim_waits_for_the_first_and_reads_its_result(tmp_path: Path) -> None:
    first, second = JobStore(tmp_path), JobStore(tmp_path)
    assert first.load_or_claim("k") is None  # nothing stored: first computes
    seen: list[dict[str, Any] | None] = []
    waiter = threading.Thread(target=lambda: seen.append(second.load_or_claim("k")))
    waiter.start()
    waiter.join(timeout=1.0)
    assert waiter.is_alive()  # blocked on the first one's lock, not computing
    first.save("k", {"task": 1}, {"success": True, "exec_length": 4})
    first.release("k")
    waiter.join(timeout=30)
    assert seen == [{"success": True, "exec_length": 4}]
    second.release("k")
    assert JobStore(tmp_path).load_or_claim("other") is None  # locks are per key


def test_a_killed_claimant_does_not_block_the_next(tmp_path: Path) -> None:
    code = (
        "import sys, time; from flows.store import JobStore; "
        f"s = JobStore({str(tmp_path)!r}); s.load_or_claim('k'); print('claimed', flush=True); "
        "time.sleep(600)"
    )
    holder = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, cwd=REPO
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "claimed"
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    finally:
        if holder.poll() is None:
            holder.kill()
    store = JobStore(tmp_path)
    assert store.load_or_claim("k") is None  # the lock died with its process
    store.release("k")


def test_a_running_sweeps_directory_is_refused_a_dead_ones_resumed(tmp_path: Path) -> None:
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
    try:
        SweepState(str(tmp_path), time.time(), sleeper.pid).save()
        with pytest.raises(SystemExit) as stop:
            _refuse_running_sweep(tmp_path)
        assert stop.value.code == 2
    finally:
        sleeper.kill()
        sleeper.wait()
    _refuse_running_sweep(tmp_path)  # its sweep is gone (kill -9): resuming is fine


def _summaries(out: Path) -> list[dict[str, Any]]:
    paths = sorted(out.glob("multiruns/*/*/.twostep/summary.json"))
    return [json.loads(p.read_text()) for p in paths]


def test_two_identical_sweeps_at_once_keep_apart_and_compute_each_job_once(
    data: Path, tmp_path: Path
) -> None:
    """Before: one multirun dir (named to the second), progress `[3/1 done`, both
    sweeps computed every job; on a fresh MLflow store both created its tables at once
    and a job was not logged."""
    out = tmp_path / "out"
    command = [
        str(TWOSTEP), "-m", "task=1,3", "method=sa", f"data.root={data}",
        f"output.root={out}", *FAST,
    ]  # fmt: skip
    sweeps = [
        subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        for _ in range(2)
    ]
    outputs = [sweep.communicate(timeout=240) for sweep in sweeps]
    for sweep, (stdout, stderr) in zip(sweeps, outputs, strict=True):
        assert sweep.returncode == 0, stdout + stderr
        assert "/1 done" not in stdout and "/4 done" not in stdout
        assert "not logged to MLflow" not in stderr, stderr
    summaries = _summaries(out)
    assert len(summaries) == 2  # a directory each
    assert all(s["jobs_total"] == 2 and s["jobs_done"] == 2 for s in summaries)
    # Each of the 2 jobs was computed by exactly one of the sweeps; the other reused it.
    assert sum(s["jobs_reused"] for s in summaries) == 2
    assert len(list((out / "jobs").glob("*/result.json"))) == 2
    jobs, _ = _mlflow_runs(out)
    assert sorted(r.data.params["task"] for r in jobs) == ["1", "3"]  # one run per job


def _mlflow_runs(out: Path) -> tuple[list[Any], list[Any]]:
    """(job runs, sweep parent runs) of every sweep experiment in the store."""
    from mlflow.tracking import MlflowClient

    client = MlflowClient(f"sqlite:///{out}/mlflow.db")
    experiments = [e for e in client.search_experiments() if e.name.startswith("sweep ")]
    runs = [r for e in experiments for r in client.search_runs([e.experiment_id])]
    jobs = [r for r in runs if r.data.tags.get("twostep.kind") == "job"]
    return jobs, [r for r in runs if r.data.tags.get("twostep.kind") == "sweep"]


# ----------------------------------------------------------------- kill -9 and resume


def test_sweep_killed_mid_run_resumes_without_duplicates_in_mlflow(
    data: Path, tmp_path: Path
) -> None:
    """Fast version of tests/test_sweep.py's kill -9 test: 3 tiny jobs, Prefect off."""
    out = tmp_path / "out"
    command = [
        "-m", "task=1,2,3", "method=twostep", "agents=2", f"data.root={data}",
        f"output.root={out}", *FAST,
    ]  # fmt: skip
    process = subprocess.Popen(
        [str(TWOSTEP), *command], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        deadline = time.monotonic() + 200
        while not list(out.glob("multiruns/*/*/.twostep/jobs/0.json")):
            assert process.poll() is None and time.monotonic() < deadline
            time.sleep(0.02)
        process.send_signal(signal.SIGKILL)
        process.wait()
    finally:
        if process.poll() is None:
            process.kill()
    done_before = len(list(out.glob("multiruns/*/*/.twostep/jobs/*.json")))
    assert 1 <= done_before <= 3

    again = twostep(*command)
    assert again.returncode == 0, again.stdout + again.stderr
    final = _summaries(out)[-1]
    assert final["jobs_done"] == 3 and final["jobs_failed"] == 0
    assert final["jobs_reused"] >= done_before  # finished jobs were not recomputed

    jobs, parents = _mlflow_runs(out)
    assert sorted(r.data.params["task"] for r in jobs) == ["1", "2", "3"]  # no duplicate
    assert len(parents) == 1
    assert {r.data.tags["mlflow.parentRunId"] for r in jobs} == {parents[0].info.run_id}


# ----------------------------------------------------------------- PDDL messages


DOMAIN = """(define (domain bw)
 (:requirements :strips)
 (:predicates (on ?x ?y) (clear ?x))
 (:action touch :parameters (?x) :precondition (clear ?x) :effect (clear ?x)))
"""


def _problem(goal: str) -> str:
    return f"(define (problem p) (:domain bw)\n (:objects b1 b2)\n (:init (clear b1))\n (:goal {goal}))\n"


def _load(tmp_path: Path, domain: str | bytes, problem: str | bytes) -> PDDLError:
    for name, text in (("domain.pddl", domain), ("p01.pddl", problem)):
        path = tmp_path / name
        path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(PDDLError) as error:
        load_problem(tmp_path / "domain.pddl", tmp_path / "p01.pddl")
    return error.value


def test_unknown_predicate_in_the_goal_is_named_with_file_and_line(tmp_path: Path) -> None:
    error = _load(tmp_path, DOMAIN, _problem("(and (levitating b1))"))
    assert str(error).startswith(f"{tmp_path / 'p01.pddl'}:4: unknown predicate 'levitating'")


def test_unknown_object_in_the_goal_is_named(tmp_path: Path) -> None:
    error = _load(tmp_path, DOMAIN, _problem("(and (clear b3))"))
    assert str(error).startswith(f"{tmp_path / 'p01.pddl'}:4: unknown object 'b3'")


def test_derived_predicates_are_read_and_misuse_is_named(tmp_path: Path) -> None:
    # Derived predicates are supported (issue 17): (on ?x ?y) holds whenever ?x is clear.
    domain = DOMAIN.replace(
        "(:action", "(:derived (on ?x ?y) (clear ?x))\n (:action"
    )  # line 4 of the domain
    for name, text in (("domain.pddl", domain), ("p01.pddl", _problem("(and (on b1 b2))"))):
        (tmp_path / name).write_text(text)
    problem = load_problem(tmp_path / "domain.pddl", tmp_path / "p01.pddl")
    assert ("on", "b1", "b2") in problem.init and problem.goal.holds(problem.init)
    # Fast Downward evaluates only the derived facts a goal or an action uses: a subgoal
    # on another one is refused, not silently never true
    with pytest.raises(PDDLError, match=r"\(on b1 b1\) is a derived fact the task never"):
        parse_goal("(on b1 b1)", problem)
    # an action may not change a derived predicate (Fast Downward rejects it too)
    misuse = domain.replace(":effect (clear ?x)", ":effect (on ?x ?x)")
    error = _load(tmp_path, misuse, _problem("(and (clear b1))"))
    assert error.source == str(tmp_path / "domain.pddl") and error.line == 5
    assert "changes the derived predicate 'on'" in error.message


def test_an_error_in_a_forall_effect_names_the_file(tmp_path: Path) -> None:
    domain = DOMAIN.replace(":strips", ":adl").replace(
        ":effect (clear ?x)", ":effect (forall (?y) (glowing ?y))"
    )
    error = _load(tmp_path, domain, _problem("(and (clear b1))"))
    assert error.source == str(tmp_path / "domain.pddl"), str(error)


@pytest.mark.parametrize("which", ["domain", "problem"])
def test_a_binary_file_is_named(tmp_path: Path, which: str) -> None:
    binary = b"\x89PNG\r\n\x1a\n\x00\xff\xfe"
    domain = binary if which == "domain" else DOMAIN
    problem = binary if which == "problem" else _problem("(and (clear b1))")
    error = _load(tmp_path, domain, problem)
    name = "domain.pddl" if which == "domain" else "p01.pddl"
    assert error.source == str(tmp_path / name) and "not a text file" in error.message


def test_a_binary_task_file_exits_2_with_its_name(data: Path, tmp_path: Path) -> None:
    (data / "blocksworld" / "p09.pddl").write_bytes(b"\x00\xff\xfe binary")
    try:
        done = twostep(
            "task=9", "mlflow.enabled=false", f"data.root={data}",
            f"output.root={tmp_path / 'out'}", *FAST,
        )  # fmt: skip
    finally:
        (data / "blocksworld" / "p09.pddl").unlink()
    line = one_error_line(done)
    assert "p09.pddl" in line and "not a text file" in line


# ----------------------------------------------------------------- issue 20, finding 7


@pytest.mark.parametrize("method", ["sa", "ma", "twostep"])
def test_agent_predicates_the_domain_lacks_are_an_error_for_every_method(
    data: Path, tmp_path: Path, method: str
) -> None:
    """Before: `domain.agent_predicates=[nonexistent]` was accepted and stored (the
    twostep-score command refuses the same value)."""
    out = tmp_path / "out"
    done = twostep(
        f"method={method}", "task=1", "domain.agent_predicates=[holding,levitating]",
        "mlflow.enabled=false", f"data.root={data}", f"output.root={out}", *FAST,
    )  # fmt: skip
    line = one_error_line(done)
    assert line.startswith("error: domain.agent_predicates: levitating not in domain 'blocksworld'")
    assert "its predicates: arm-empty, clear, holding, on, on-table" in line
    assert not list((out / "jobs").glob("*/result.json"))  # nothing stored
    (result,) = out.glob("runs/*/*/result.json")
    assert "plan_calls" not in json.loads(result.read_text())  # refused before planning


def test_a_stored_entry_that_is_not_a_whole_result_is_computed_again(
    data: Path, tmp_path: Path
) -> None:
    """Before: a stored `{}` replayed as `None pNone None | N=None | FAILED (None: None)`."""
    out = tmp_path / "out"
    args = ["method=sa", "task=1", "mlflow.enabled=false", f"data.root={data}",
            f"output.root={out}", *FAST]  # fmt: skip
    first = twostep(*args)
    assert first.returncode == 0, first.stderr
    (stored,) = (out / "jobs").glob("*/result.json")
    whole = json.loads(stored.read_text())
    stored.write_text("{}")
    again = twostep(*args)
    assert again.returncode == 0, again.stderr
    assert again.stdout.startswith("blocksworld-p01-sa-n1-s0 | success")
    assert "reused" not in again.stdout.splitlines()[0]  # computed, not replayed
    assert f"job store entry {stored} is not a complete result" in again.stderr
    again_stored = json.loads(stored.read_text())  # the entry is whole again (new timings)
    assert again_stored["plans"] == whole["plans"] and again_stored["success"] is True


def test_score_says_that_no_agent_predicates_means_every_fact_is_shared(
    data: Path, tmp_path: Path
) -> None:
    """Before: without --agent-predicates the arm was silently shared by the agents."""
    plan = tmp_path / "agent0.plan"
    plan.write_text("(pickup a)\n")
    files = [data / "blocksworld" / "domain.pddl", data / "blocksworld" / "p03.pddl", plan]
    score = Path(sys.executable).parent / "twostep-score"
    silent = subprocess.run(
        [str(score), *map(str, files)], capture_output=True, text=True, timeout=120
    )
    assert silent.returncode == 0, silent.stderr
    assert "no --agent-predicates: every fact is shared by all agents" in silent.stderr
    explicit = subprocess.run(
        [str(score), *map(str, files), "--agent-predicates", "none"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert explicit.stdout == silent.stdout and explicit.stderr == ""


def test_an_unquoted_on_in_a_yaml_domain_config_is_named_with_the_fix() -> None:
    # YAML reads `agent_predicates: [on, holding]` as [True, "holding"] (the config then
    # holds "True"): refused with the reason and the fix. Quoted, `on` is blocksworld's own.
    from omegaconf import OmegaConf

    from flows.build import JobError, check_task
    from twostep.tasks.benchmark import load_task

    task = load_task("blocksworld", 1, REPO / "data")
    cfg = compose_config("domain=blocksworld")
    unquoted = OmegaConf.merge(cfg, OmegaConf.create("domain:\n  agent_predicates: [on, holding]"))
    with pytest.raises(JobError) as raised:
        check_task(unquoted, task)
    assert str(raised.value).startswith("domain.agent_predicates: True not in domain")
    assert "reads unquoted on/off/yes/no/true/false as booleans: quote the name" in str(
        raised.value
    )
    quoted = OmegaConf.merge(cfg, OmegaConf.create("domain:\n  agent_predicates: ['on', holding]"))
    check_task(quoted, task)
