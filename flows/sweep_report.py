"""A sweep's report (Fig. 3-style charts and summary tables of its result files, in
``<sweep dir>/report``), drawn at the sweep's end by a process started with the sweep.

Importing pandas and matplotlib and drawing the first charts (its fonts, its PDF and SVG
backends) took 4-7 s after a sweep's last job on a busy 2-core machine. The process
(:class:`Drawing`) starts with the sweep and does the importing meanwhile; told to draw
(:meth:`Drawing.files`), it draws the finished sweep's results while the launching process
prints the summary and imports MLflow's client for the parent run, which then gets the
report's files as artifacts. A sweep that ends otherwise (Ctrl-C, ``kill -9``) closes the
process's input: it ends without drawing.

    python -m flows.sweep_report SWEEP_DIR   # ready, then draws when a line comes on stdin
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
from pathlib import Path


def draw(sweep_dir: Path) -> list[tuple[Path, str | None]]:
    """The sweep's report as (file, artifact folder) pairs for its parent run; none (and
    a warning) when there is nothing to report."""
    from flows.report_sources import RUN_PARAMS, load_runs_from_sweep_dir
    from twostep.report import ReportInputError, build_report, write_report

    out = sweep_dir / "report"
    try:
        report = build_report(load_runs_from_sweep_dir(sweep_dir), params=RUN_PARAMS)
        paths = write_report(report, out, f"TwoStep sweep {sweep_dir.name}", f"`{sweep_dir}`")
    except ReportInputError:
        return []
    except Exception as error:  # the jobs are recorded; the report is extra
        print(f"warning: no sweep report: {error}", file=sys.stderr)
        return []
    return [(path, "report") for path in paths if path.is_file()]


class Drawing:
    """The process that draws the sweep's report (see the module docstring)."""

    def __init__(self, sweep_dir: Path) -> None:
        self.sweep_dir = sweep_dir
        try:
            self.process: subprocess.Popen[str] | None = subprocess.Popen(
                [sys.executable, "-m", "flows.sweep_report", str(sweep_dir)],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                text=True,
            )  # stderr: the console's (its warning)
        except OSError:
            self.process = None

    def start(self) -> None:
        """Draw now (the sweep's results are all written)."""
        if self.process is not None and self.process.stdin is not None:
            try:
                self.process.stdin.write("draw\n")
                self.process.stdin.flush()
            except OSError:  # it died: files() draws here
                self.process = None

    def files(self) -> list[tuple[Path, str | None]]:
        """The report's files, once drawn (:meth:`start` first)."""
        if self.process is None:
            return draw(self.sweep_dir)  # no process could start: drawn here
        out, _ = self.process.communicate()
        try:
            listed = json.loads(out.strip().splitlines()[-1]) if out.strip() else []
        except ValueError:
            listed = []
        return [(Path(path), folder) for path, folder in listed]

    def cancel(self) -> None:
        """No report: the process ends (without drawing, unless :meth:`start` asked)."""
        if self.process is not None:
            self.process.communicate()  # its input closed: it ends


def _prepare() -> None:
    """What drawing the first report would load: pandas, matplotlib and its backends and
    fonts."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.backends.backend_pdf
    import matplotlib.backends.backend_svg
    import matplotlib.font_manager
    import matplotlib.pyplot

    import twostep.report  # noqa: F401

    matplotlib.font_manager.fontManager.findfont("DejaVu Sans")


def main(argv: list[str]) -> int:
    from flows.environment import quiet_defaults

    quiet_defaults()
    with contextlib.suppress(Exception):  # drawing says what is wrong, if anything
        _prepare()
    if not sys.stdin.readline().strip():
        return 0  # the sweep ended without asking
    files = draw(Path(argv[0]))
    try:
        print(json.dumps([[str(path), folder] for path, folder in files]), flush=True)
    except BrokenPipeError:  # the sweep ended without reading them: nothing to say
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no flush error at exit
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
