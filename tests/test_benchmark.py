"""twostep.tasks.benchmark: the LLM+P layout, unknown names listed in one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.data import make_root
from twostep.tasks.benchmark import BenchmarkError, list_domains, list_tasks, load_task


def test_layout_is_read(tmp_path: Path) -> None:
    root = make_root(tmp_path)
    assert list_domains(root) == ["blocks"]
    assert list_tasks("blocks", root) == [1, 3]
    task = load_task("blocks", 1, root)
    assert task.name == "blocks/p01"
    assert task.task_nl == "Put a on b." and task.domain_nl == "Blocks on a table."
    assert task.example_plan == ("(pickup a)",)
    assert task.example_nl == ""  # missing files are empty, not errors


def test_unknown_domain_and_task_list_what_exists(tmp_path: Path) -> None:
    root = make_root(tmp_path)
    with pytest.raises(BenchmarkError) as info:
        load_task("blockworld", 1, root)
    assert "domains: blocks" in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(BenchmarkError) as info:
        load_task("blocks", 2, root)
    assert "tasks: 1..3" in str(info.value)


def test_generated_data_set_is_complete(data_root: Path) -> None:
    symbolic = ["barman", "blocksworld", "grippers", "termes", "tyreworld"]
    assert list_domains(data_root) == ["alfworld", *symbolic]  # + the embodied kitchen
    for domain in list_domains(data_root):
        tasks = [1, 2, 3, 4] if domain == "alfworld" else list(range(1, 21))  # Table II: 4
        assert list_tasks(domain, data_root) == tasks
        task = load_task(domain, 1, data_root)
        assert task.task_nl and task.domain_nl and task.example_nl and task.example_plan
