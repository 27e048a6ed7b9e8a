"""The README's and the tutorial's samples come from the commands printed beside them.

* The code block under "As a library" in the tutorial (``docs/tutorial/index.md``) is read
  and executed as it stands; each run it makes is then re-validated by simulation
  (``check_run``) and, as a sequential plan of the N-agent compilation, by
  unified-planning's validator.
* The demo's output in the README (and on the site's home page) is what the demo's command
  prints today: ``twostep domain=blocksworld task=6 method=plan-deal agents=2`` is run as a
  user runs it, and every line must equal the README's, but for the planning time (a
  timing) and the run directory's date and time.
* The README's prose holds no results number: its numbers are the generated headline table
  (``make results``, checked in ``tests/test_docs_site.py``) or command outputs in code
  blocks; the README stays a landing page of at most 200 lines.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from tests.support.docs import NUMBER, prose
from tests.support.plans import up_validate_run
from tools import results
from twostep.methods import check_run

REPO = Path(__file__).resolve().parent.parent
README = REPO / "README.md"
TUTORIAL = REPO / "docs" / "tutorial" / "index.md"
HOME = REPO / "docs" / "index.md"
DEMO = "twostep domain=blocksworld task=6 method=plan-deal agents=2"


def library_example() -> str:
    text = TUTORIAL.read_text()
    section = text.split("\n## As a library\n", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.DOTALL)
    assert blocks, "no python block under 'As a library'"
    return str(blocks[0])


def test_the_library_example_runs(data_root: Path, capsys: pytest.CaptureFixture[str]) -> None:
    names: dict[str, Any] = {}
    exec(compile(library_example(), "docs/tutorial/index.md", "exec"), names)  # as printed
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


def code_blocks(text: str) -> list[tuple[int, str, list[str]]]:
    """Each fenced block of ``text``: (the line it opens on, its language, its lines)."""
    blocks, lines, opened = [], text.splitlines(), None
    for number, line in enumerate(lines):
        if line.startswith("```"):
            if opened is None:
                opened = (number, line[3:].strip())
            else:
                blocks.append((opened[0], opened[1], lines[opened[0] + 1 : number]))
                opened = None
    return blocks


def demo_block(text: str) -> list[str]:
    """The output block printed beside the demo's command (named just before it)."""
    for start, language, lines in code_blocks(text):
        if not language and lines and lines[0].startswith("blocksworld-p06-"):
            before = " ".join(" ".join(text.splitlines()[max(0, start - 6) : start]).split())
            assert DEMO in before.replace("`", ""), "the demo's command is not beside its output"
            return lines
    raise AssertionError("no demo output block")


def masked(lines: list[str]) -> list[str]:
    """Timings and the run directory's date and time masked; nothing else."""
    out = []
    for line in lines:
        line = re.sub(r"planning_time=\d+\.\d+s", "planning_time=<s>", line)
        line = re.sub(
            r"(result: ).*?(outputs/runs/)\S+?/\S+?(_blocksworld)", r"\1\2<d>/<t>\3", line
        )
        out.append(line.rstrip())
    return out


def test_the_demo_prints_what_the_readme_shows(tmp_path: Path) -> None:
    env = {**os.environ, "NO_COLOR": "1", "COLUMNS": "120"}
    twostep = Path(sys.executable).with_name("twostep")
    done = subprocess.run([str(twostep), *DEMO.split()[1:]], capture_output=True, text=True,
                          cwd=tmp_path, env=env, timeout=300, check=True)  # fmt: skip
    printed = masked(done.stdout.strip().splitlines())
    for page in (README, HOME):
        shown = masked(demo_block(page.read_text()))
        assert shown == printed, page.name
    # the mask is narrow: the schedule and the lengths are compared as printed
    assert "exec_length=7" in printed[0] and len(printed) == 11


def test_the_readme_is_a_landing_page_with_no_typed_results_number() -> None:
    text = README.read_text()
    assert len(text.splitlines()) <= 200
    # the headline table and the sweep's cost are generated (make results) and compared
    # in test_docs_site
    for begin, end, _ in results.GENERATED_BLOCKS:
        before, rest = text.split(begin, 1)
        text = before + rest.split(end, 1)[1]
    numbers = NUMBER.findall(prose(text))
    assert set(numbers) <= {"3.11", "3.12", "127.0.0.1"}, numbers  # Python versions, an address
    # the fresh-machine commands come first
    first = code_blocks(text)[0]
    assert first[1] == "bash" and [line.split()[:2] for line in first[2]] == [
        ["make", "demo"],
        ["make", "test"],
    ]
