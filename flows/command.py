"""The ``twostep`` command's entry point: a single run that logs to MLflow starts its
logging process before anything heavy is imported.

Importing MLflow's client in that process (:mod:`flows.tracking.worker`) takes about as
long as a short run; started here, before Hydra and the library are imported by
:mod:`flows.cli`, it overlaps those imports too, not only the config and the planning.
Everything else is :func:`flows.cli.main`.
"""

from __future__ import annotations

import sys


def logs_a_single_run(arguments: list[str]) -> bool:
    """Whether the command line is a single run that logs to MLflow (no Hydra flag such as
    ``-m`` or ``--help``, MLflow not turned off)."""
    if any(a.startswith("-") for a in arguments):
        return False
    return not any(a.replace(" ", "").lower() == "mlflow.enabled=false" for a in arguments)


def main() -> None:
    if logs_a_single_run(sys.argv[1:]):
        from flows.tracking.worker import TrackingWorker

        TrackingWorker.prestart()  # imports MLflow on the other core meanwhile
    from flows.cli import main as run_command

    run_command()
