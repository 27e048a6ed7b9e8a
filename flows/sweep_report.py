"""A sweep's report (Fig. 3-style charts and summary tables of its result files, in
``<sweep dir>/report``), drawn in a process of its own at the sweep's end.

Drawing imports matplotlib and draws three formats (3-5 s on a busy 2-core machine); the
launching process meanwhile prints the summary and the results table and imports MLflow's
client for the parent run, which then gets the report's files as artifacts.

    python -m flows.sweep_report SWEEP_DIR      # prints the files, one JSON list
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path


def draw(sweep_dir: Path) -> list[tuple[Path, str | None]]:
    """The sweep's report as (file, artifact folder) pairs for its parent run; none (and
    a warning) when there is nothing to report."""
    from twostep.report import (
        ReportInputError,
        build_report,
        load_runs_from_sweep_dir,
        write_report,
    )

    out = sweep_dir / "report"
    try:
        report = build_report(load_runs_from_sweep_dir(sweep_dir))
        paths = write_report(report, out, f"TwoStep sweep {sweep_dir.name}", f"`{sweep_dir}`")
    except ReportInputError:
        return []
    except Exception as error:  # the jobs are recorded; the report is extra
        print(f"warning: no sweep report: {error}", file=sys.stderr)
        return []
    return [(path, "report") for path in paths if path.is_file()]


class Drawing:
    """The report being drawn by ``python -m flows.sweep_report`` (:meth:`files` waits)."""

    def __init__(self, sweep_dir: Path) -> None:
        self.sweep_dir = sweep_dir
        try:
            self.process: subprocess.Popen[str] | None = subprocess.Popen(
                [sys.executable, "-m", "flows.sweep_report", str(sweep_dir)],
                stdin=subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                text=True,
            )  # stderr: the console's (its warning)
        except OSError:
            self.process = None

    def files(self) -> list[tuple[Path, str | None]]:
        if self.process is None:
            return draw(self.sweep_dir)  # no process could start: drawn here
        out, _ = self.process.communicate()
        try:
            listed = json.loads(out.strip().splitlines()[-1]) if out.strip() else []
        except ValueError:
            listed = []
        return [(Path(path), folder) for path, folder in listed]


def main(argv: list[str]) -> int:
    from flows.environment import quiet_defaults

    quiet_defaults()
    files = draw(Path(argv[0]))
    print(json.dumps([[str(path), folder] for path, folder in files]), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
