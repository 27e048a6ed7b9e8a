"""The README's library example runs as printed, and its schedules are valid.

The code block under "As a library" is read from README.md and executed as it stands;
each run it makes is then re-validated by simulation (``check_run``) and, as a
sequential plan of the N-agent compilation, by unified-planning's validator.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from tests.test_plan_split import up_validate_run
from twostep.methods import check_run

README = Path(__file__).resolve().parent.parent / "README.md"


def library_example() -> str:
    text = README.read_text()
    section = text.split("\n## As a library\n", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.DOTALL)
    assert blocks, "no python block under 'As a library'"
    return str(blocks[0])


def test_the_library_example_runs(data_root: Path, capsys: pytest.CaptureFixture[str]) -> None:
    names: dict[str, Any] = {}
    exec(compile(library_example(), "README.md", "exec"), names)  # the snippet as printed
    printed = capsys.readouterr().out.split()
    sa, twostep, deal = names["sa"], names["ts"], names["deal"]
    assert printed[:3] == [str(sa.exec_length), str(twostep.exec_length), str(deal.exec_length)]
    facts, task = names["agent_facts"], names["task"]
    for run in (sa, twostep, deal):
        assert run.success
        check_run(task.problem, run, facts)
        up_validate_run(task.problem, run, facts)
    # one agent's plan is the SA plan; the two multi-agent schedules are no longer
    assert twostep.exec_length <= sa.exec_length and deal.exec_length <= sa.exec_length
