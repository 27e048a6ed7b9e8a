"""Shared fixtures: the project's data set and small named example problems."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from twostep.tasks.benchmark import BenchmarkTask

os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
os.environ.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")
os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
# twostep-score keeps parsed tasks in a user cache folder: never the tester's home here.
os.environ.setdefault("TWOSTEP_CACHE_DIR", tempfile.mkdtemp(prefix="twostep-test-cache-"))

REPO = Path(__file__).resolve().parent.parent
DATA = REPO / "data"
FIXTURES = Path(__file__).resolve().parent / "fixtures"

BLOCKS_DOMAIN = """
(define (domain blocks)
  (:requirements :strips)
  (:predicates (clear ?x) (on-table ?x) (arm-empty) (holding ?x) (on ?x ?y))
  (:action pickup :parameters (?b)
    :precondition (and (clear ?b) (on-table ?b) (arm-empty))
    :effect (and (holding ?b) (not (clear ?b)) (not (on-table ?b)) (not (arm-empty))))
  (:action putdown :parameters (?b)
    :precondition (holding ?b)
    :effect (and (clear ?b) (arm-empty) (on-table ?b) (not (holding ?b))))
  (:action stack :parameters (?b ?under)
    :precondition (and (clear ?under) (holding ?b))
    :effect (and (arm-empty) (clear ?b) (on ?b ?under) (not (clear ?under)) (not (holding ?b))))
  (:action unstack :parameters (?b ?under)
    :precondition (and (on ?b ?under) (clear ?b) (arm-empty))
    :effect (and (holding ?b) (clear ?under) (not (on ?b ?under)) (not (clear ?b)) (not (arm-empty)))))
"""


def own_task(root: Path, name: str, domain: str, problem: str) -> BenchmarkTask:
    """A domain of the test's own (``domain``, its PDDL text) with ``problem`` as task 1, in
    folder ``name`` of ``root``."""
    from twostep.tasks.benchmark import load_task  # after the environment above is set

    folder = root / name
    folder.mkdir(parents=True)
    (folder / "domain.pddl").write_text(domain)
    (folder / "domain.nl").write_text(name)
    (folder / "p01.pddl").write_text(problem)
    return load_task(name, 1, root)


def blocks_problem(init: str, goal: str, objects: str = "a b c d") -> str:
    return f"(define (problem p) (:domain blocks) (:objects {objects}) (:init {init}) (:goal (and {goal})))"


@pytest.fixture(scope="session")
def data_root() -> Path:
    if not (DATA / "blocksworld" / "domain.pddl").is_file():
        pytest.skip("data/ has not been generated")
    return DATA


@pytest.fixture(scope="session")
def quirks_root() -> Path:
    return FIXTURES / "llmp_quirks"


@pytest.fixture(scope="session")
def prefect_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """One Prefect server for the session's integration tests; stopped by PID."""
    from flows.servers import (
        ServerSettings,
        pid_alive,
        spawn_server,
        stop_server,
        wait_until_healthy,
    )

    home = tmp_path_factory.mktemp("prefect-home")
    info = spawn_server(
        ServerSettings(home=str(home), startup_timeout_s=240), owner_pid=os.getpid()
    )
    try:
        wait_until_healthy(info)
        yield info.api_url
    finally:
        stop_server(info)
        assert info.pid is not None and not pid_alive(info.pid)
