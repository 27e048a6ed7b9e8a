"""tools/record.py's printed-output records: a bench's printed tables read back as rows
(``|`` tables and space-aligned ones), its other lines kept in order, a live run captured
with ``--json`` and printed output kept from before converted once (``--from-txt``).

The expected rows are written out by hand from the sample outputs below."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from tools import record  # noqa: E402

PIPES = """\
# bench/bench_x.py --seeds 2
task | N | SA | fallback
---|---|---|---
blocksworld p01 | 4 | 8 | -
barman p20 | 16 | 92 | no deal shorter [piece 0: none]
total 3 s
"""

ALIGNED = """\
scenario        jobs  completed  MLflow runs  tracebacks
--------------------------------------------------------
bad-files         36         36            -           0
hostile-inputs    24         24            -           0

bad-files: 218 s
"""

# Header cells run together ("plan s planner s"): cut at the data columns' right edges.
RUN_TOGETHER = """\
task                parse s   plan s planner s  status
blocksworld/p01       1.043    0.602     0.170  valid
grippers/p01          1.018    0.720     0.170  valid
"""


def test_a_pipe_table_becomes_rows_and_the_rest_text_in_order() -> None:
    parsed = record.parse_printed(PIPES)
    assert parsed["rows"] == [
        {"task": "blocksworld p01", "N": "4", "SA": "8", "fallback": "-"},
        {
            "task": "barman p20",
            "N": "16",
            "SA": "92",
            "fallback": "no deal shorter [piece 0: none]",
        },
    ]
    assert parsed["blocks"] == [
        {"lines": ["# bench/bench_x.py --seeds 2"]},
        {"columns": ["task", "N", "SA", "fallback"], "first": 0, "count": 2},
        {"lines": ["total 3 s"]},
    ]


def test_a_space_aligned_table_with_a_rule_becomes_rows() -> None:
    parsed = record.parse_printed(ALIGNED)
    assert parsed["rows"] == [
        {"scenario": "bad-files", "jobs": "36", "completed": "36", "MLflow runs": "-",
         "tracebacks": "0"},
        {"scenario": "hostile-inputs", "jobs": "24", "completed": "24", "MLflow runs": "-",
         "tracebacks": "0"},
    ]  # fmt: skip
    assert parsed["blocks"][-1] == {"lines": ["", "bad-files: 218 s"]}


def test_header_cells_that_run_together_are_cut_at_the_data_columns() -> None:
    (first, _) = record.parse_printed(RUN_TOGETHER)["rows"]
    assert first == {"task": "blocksworld/p01", "parse s": "1.043", "plan s": "0.602",
                     "planner s": "0.170", "status": "valid"}  # fmt: skip


@pytest.mark.parametrize(
    "text",
    [
        "run 1: first 27.4 s | reused 4/4 | server started: False\n"
        "run 2: first 24.3 s | reused 4/4 | server started: False\n",  # a log line, not a table
        "planner: Fast Downward (up-fast-downward 1.0.0), alias lama\n"
        "domain  subgoals\nbarman  120  120 (100.0%)\nall  60  56 (93.3%)\n",  # no fit
    ],
)
def test_lines_that_only_look_like_a_table_stay_text(text: str) -> None:
    parsed = record.parse_printed(text)
    assert parsed["rows"] == []
    assert [line for b in parsed["blocks"] for line in b["lines"]] == text.splitlines()


def test_a_captured_run_is_the_record_of_what_it_printed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "x.json"
    with record.capture(out, title="T"):
        print(PIPES, end="")
    assert capsys.readouterr().out == PIPES  # still printed
    data = json.loads(out.read_text())
    assert data["title"] == "T"
    assert data["rows"] == record.parse_printed(PIPES)["rows"]
    assert data["run"]["command"].startswith("python ")
    assert len(data["run"]["load_end"]) == 3


def test_without_a_path_nothing_is_written(tmp_path: Path) -> None:
    with record.capture(None):
        print("a | b\n1 | 2")
    assert list(tmp_path.iterdir()) == []


def test_a_converted_record_says_where_it_came_from_and_renders_its_tables(
    tmp_path: Path,
) -> None:
    txt = tmp_path / "old.txt"
    txt.write_text("first run\n" + PIPES)
    data = record.from_printed(txt, "python bench/bench_x.py", "Old", date="2026-11-20",
                               load=[1.0, 2.0, 3.0], lines=(2, 7))  # fmt: skip
    run = data["run"]
    assert (run["command"], run["date"], run["machine"]) == (
        "python bench/bench_x.py",
        "2026-11-20",
        None,
    )
    assert run["converted_from"] == str(txt)  # outside the repository: the path as given
    header = record.run_lines(run, "docs/bench/old.json")
    assert "- load average (1 / 5 / 15 min): 1.00 / 2.00 / 3.00, as printed" in header
    assert any("the machine was not recorded" in line for line in header)
    page = record.printed_page([data], figure=None)
    assert page[:2] == ["## Old", ""]
    assert "| barman p20 | 16 | 92 | no deal shorter [piece 0: none] |" in page
    assert "first run" not in "\n".join(page)  # line 1 left out
