"""Job identity (flows/identity.py): which keys count, the key, the names, what is stored."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from flows import identity

BASE: dict[str, Any] = {
    "domain": {"name": "grippers", "agent_predicates": ["free"]},
    "method": {"name": "twostep"},
    "decomposer": {"name": "llm", "link_degree": 2},
    "llm": {"model": "openai/gpt-4o", "cache_dir": "/a", "max_retries": 4, "script": None},
    "planner": {"alias": "lama-first", "time_limit_s": 60.0},
    "data": {"root": "/data"},
    "task": 9,
    "agents": 2,
    "seed": 0,
}


def with_(config: dict[str, Any], dotted: str, value: Any) -> dict[str, Any]:
    """A deep copy of ``config`` with one dotted key set."""
    head, _, rest = dotted.partition(".")
    out = dict(config)
    out[head] = with_(dict(config.get(head) or {}), rest, value) if rest else value
    return out


@pytest.mark.parametrize(
    "dotted, value",
    [
        ("output.root", "/elsewhere"),
        ("mlflow.tracking_uri", "http://x:5000"),
        ("orchestration.prefect", True),
        ("orchestration.task_runner", "dask"),
        ("hydra.run.dir", "/tmp/x"),
        ("experiment", "paper"),
        ("llm.cache_dir", "/b"),
        ("llm.max_retries", 9),
    ],
)
def test_where_and_how_keys_do_not_change_the_key(dotted: str, value: Any) -> None:
    assert not identity.is_identity_key(dotted)
    assert identity.job_key(BASE) == identity.job_key(with_(BASE, dotted, value))


@pytest.mark.parametrize(
    "dotted, value",
    [
        ("task", 10),
        ("seed", 1),
        ("agents", 3),
        ("planner.alias", "lama"),
        ("planner.time_limit_s", 30.0),
        ("llm.model", "anthropic/claude"),
        ("decomposer.link_degree", 1),
        ("data.root", "/other-data"),
    ],
)
def test_what_keys_change_the_key(dotted: str, value: Any) -> None:
    assert identity.is_identity_key(dotted)
    assert identity.job_key(BASE) != identity.job_key(with_(BASE, dotted, value))


def test_keys_the_method_never_reads_do_not_change_the_key() -> None:
    sa = with_(BASE, "method", {"name": "sa"})
    # SA reads neither the decomposer nor the LLM settings ...
    assert identity.job_key(sa) == identity.job_key(with_(sa, "llm.model", "other"))
    assert identity.job_key(sa) == identity.job_key(with_(sa, "decomposer.name", "expert"))
    # ... TwoStep with goal-split reads the decomposer but not the LLM.
    split = with_(BASE, "decomposer.name", "goal-split")
    assert identity.job_key(split) == identity.job_key(with_(split, "llm.model", "other"))
    assert identity.job_key(split) != identity.job_key(with_(split, "decomposer.link_degree", 1))


def test_the_same_config_gives_the_same_key_in_any_key_order() -> None:
    reordered = dict(reversed(list(BASE.items())))
    assert identity.job_key(BASE) == identity.job_key(reordered)
    assert len(identity.job_key(BASE)) == 32


def test_a_file_edit_changes_the_key(tmp_path: Path) -> None:
    folder = tmp_path / "grippers"
    folder.mkdir()
    (folder / "domain.pddl").write_text("(define (domain g))")
    problem = folder / "p09.pddl"
    problem.write_text("(define (problem p) (:goal (at b1 roomb)))")
    config = {**with_(BASE, "data.root", str(tmp_path)), "method": {"name": "sa"}}
    files = identity.job_input_files(config, problem)
    assert set(files) == {"domain", "problem"}
    before = identity.job_key(config, identity.input_digests(files))
    assert before == identity.job_key(config, identity.input_digests(files))  # unchanged: same
    problem.write_text("(define (problem p) (:goal (at b1 rooma)))")
    after = identity.job_key(config, identity.input_digests(files))
    assert after != before


def test_input_files_follow_the_decomposer(tmp_path: Path) -> None:
    problem = tmp_path / "grippers" / "p09.pddl"
    root = with_(BASE, "data.root", str(tmp_path))
    expert = identity.job_input_files(with_(root, "decomposer.name", "expert"), problem)
    assert expert["expert"] == tmp_path / "grippers" / "expert.yaml"
    script = tmp_path / "answers.yaml"
    llm = identity.job_input_files(with_(root, "llm.script", str(script)), problem)
    assert llm["llm_script"] == script and llm["problem_nl"] == problem.with_suffix(".nl")
    prompts = sorted(k for k in llm if k.startswith("prompt:"))
    assert prompts, "the LLM prompts are inputs of an LLM job"
    sa = identity.job_input_files(with_(root, "method", {"name": "sa"}), problem)
    assert set(sa) == {"domain", "problem"}
    assert identity.input_digests({"x": tmp_path / "nope"}) == {"x": "missing"}


def test_unfinished_results_are_not_stored() -> None:
    assert identity.is_storable({"status": "solved", "success": True})
    assert identity.is_storable({"status": "timeout", "success": False})
    assert identity.is_storable({"status": "unsolvable", "success": False})
    for status in ("llm_error", "error", "failed"):
        assert not identity.is_storable({"status": status, "success": False})
    assert not identity.is_storable({"status": "solved", "error": "crashed while writing"})


def test_job_names() -> None:
    """One name per job: domain, task, method, the decomposer of TwoStep, the N it runs
    and the seed, from its config or its result."""
    assert identity.job_name(BASE) == "grippers-p09-twostep-llm-n2-s0"
    sa = {**BASE, "method": {"name": "sa"}, "agents": 3}
    assert identity.job_name(sa) == "grippers-p09-sa-n1-s0"  # SA runs one agent, whatever N
    ma = {**BASE, "method": {"name": "ma"}, "seed": 2}
    assert identity.job_name(ma) == "grippers-p09-ma-n2-s2"  # no decomposer: MA reads none
    result = {"domain": "grippers", "task": 9, "method": "sa", "agents": 1, "seed": 0}
    assert identity.job_name(result) == "grippers-p09-sa-n1-s0"


def test_sweep_identity_keeps_the_experiment() -> None:
    assert identity.is_sweep_identity_key("experiment")
    assert not identity.is_sweep_identity_key("hydra/launcher")
    assert not identity.is_sweep_identity_key("+orchestration.progress")
    assert identity.is_sweep_identity_key("domain")
