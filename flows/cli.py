"""The ``twostep`` command: a Hydra app that runs one job, or a sweep with ``-m``."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from flows.config import register
from flows.job import JobError, format_schedule, format_summary, run_job
from twostep.benchmark import BenchmarkError
from twostep.pddl import PDDLError

CONF_DIR = str(Path(__file__).resolve().parent.parent / "conf")

register()


@hydra.main(config_path=CONF_DIR, config_name="config", version_base="1.3")
def app(cfg: DictConfig) -> None:
    try:
        result = run_job(cfg)
    except (BenchmarkError, PDDLError, JobError) as error:
        print(f"error: {error}", file=sys.stderr)
        sys.exit(2)
    out_dir = Path(HydraConfig.get().runtime.output_dir)
    (out_dir / "result.json").write_text(json.dumps(result.to_dict(), indent=2) + "\n")
    print(format_summary(result))
    table = format_schedule(result)
    if table:
        print(table)
    print(f"result: {out_dir / 'result.json'}")


def main() -> None:
    app()


if __name__ == "__main__":
    main()
