"""One job of a sweep the way Hydra's ``run_job`` runs it, with less copying: what the
twostep launcher calls for every job (:mod:`flows.launcher`).

Hydra's ``run_job`` (hydra-core 1.3.8, ``hydra/core/utils.py``) copies the job's config
four times (the Hydra node into ``HydraConfig`` twice, the task config, a copy of the
Hydra node for the job's return) and writes ``.hydra/config.yaml``, ``hydra.yaml`` and
``overrides.yaml`` with PyYAML's pure-Python emitter before the job starts: 40-80 ms per
job here, more than the rest of a small job's orchestration. :func:`run_job` does the
same steps in the same order with the same results, except:

* ``HydraConfig`` gets the job's config once; its output directory is then set in both
  (Hydra sets the config again, which copies its Hydra node again);
* the job's return holds ``HydraConfig``'s own Hydra node (Hydra hands out a copy);
* the three files are the same YAML text (:func:`yaml_text`: OmegaConf's own dumper,
  credentials inside URLs masked as :class:`flows.sweep_callback.SweepCallback` masks them)
  written by a thread while the job runs (it mostly waits for its planner), and are
  complete before the job's end callbacks run.

``tests/test_launcher.py`` checks that the files, the task's config and ``HydraConfig``
are the ones Hydra's ``run_job`` gives.
"""

from __future__ import annotations

import contextlib
import copy
import logging
import os
import threading
from pathlib import Path
from typing import Any

import yaml
from hydra.core.hydra_config import HydraConfig
from hydra.core.utils import JobReturn, JobRuntime, JobStatus, configure_log, env_override
from hydra.types import HydraContext, TaskFunction
from omegaconf import DictConfig, OmegaConf, open_dict, read_write
from omegaconf._utils import get_omega_conf_dumper

from twostep.util.redaction import redact_text


def yaml_text(container: Any) -> str:
    """``OmegaConf.to_yaml`` of a config already turned into plain data, credentials
    inside URLs masked."""
    text = yaml.dump(
        container,
        default_flow_style=False,
        allow_unicode=True,
        sort_keys=False,
        Dumper=get_omega_conf_dumper(),
    )
    return redact_text(str(text))


class _Writer(threading.Thread):
    """Writes the job's config files while the job runs; :meth:`finish` waits and raises
    what writing raised (as Hydra's own writing would, before the job)."""

    def __init__(self, folder: Path, files: list[tuple[str, Any]]) -> None:
        super().__init__(name="twostep-job-config-files", daemon=True)
        self.folder, self.files = folder, files
        self.error: BaseException | None = None

    def run(self) -> None:
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            for name, container in self.files:
                with open(self.folder / name, "w", encoding="utf-8") as handle:
                    handle.write(yaml_text(container))
        except BaseException as error:  # handed to the job's thread
            self.error = error

    def finish(self) -> None:
        self.join()
        if self.error is not None:
            raise self.error


def _flush_loggers() -> None:
    for reference in logging._handlerList:  # type: ignore[attr-defined]
        with contextlib.suppress(Exception):
            reference().flush()


def run_job(
    hydra_context: HydraContext,
    task_function: TaskFunction,
    config: DictConfig,
    job_dir_key: str = "hydra.sweep.dir",
    job_subdir_key: str | None = "hydra.sweep.subdir",
) -> JobReturn:
    """Run one job (see the module docstring; Hydra's ``run_job`` with fewer copies)."""
    callbacks = hydra_context.callbacks
    old_cwd = os.getcwd()
    hydra = HydraConfig.instance()
    orig_hydra_cfg = hydra.cfg
    hydra.set_config(config)
    # HydraConfig's copy: a config holding the Hydra node (typed as the node by Hydra)
    hydra_cfg: DictConfig = hydra.cfg  # type: ignore[assignment]
    output_dir = str(OmegaConf.select(config, job_dir_key))
    if job_subdir_key is not None:
        output_dir = os.path.join(output_dir, str(OmegaConf.select(config, job_subdir_key)))
    output_dir = os.path.abspath(output_dir)
    for node in (config, hydra_cfg):  # the job's config and HydraConfig's copy of its node
        with read_write(node.hydra.runtime), open_dict(node.hydra.runtime):
            node.hydra.runtime.output_dir = output_dir
    chdir = False
    writer: _Writer | None = None
    try:
        ret = JobReturn()
        task_cfg = copy.deepcopy(config)
        with read_write(task_cfg), open_dict(task_cfg):
            del task_cfg["hydra"]
        ret.cfg = task_cfg
        ret.hydra_cfg = hydra_cfg
        overrides = OmegaConf.to_container(config.hydra.overrides.task)
        assert isinstance(overrides, list)
        ret.overrides = overrides
        Path(output_dir).mkdir(parents=True, exist_ok=True)
        chdir = bool(hydra_cfg.hydra.job.chdir)
        if chdir:
            os.chdir(output_dir)
            ret.working_dir = output_dir
        else:
            ret.working_dir = os.getcwd()
        configure_log(config.hydra.job_logging, config.hydra.verbose)
        if config.hydra.output_subdir is not None:
            folder = Path(config.hydra.runtime.output_dir) / str(config.hydra.output_subdir)
            files = [
                ("config.yaml", OmegaConf.to_container(task_cfg, enum_to_str=True)),
                ("hydra.yaml", OmegaConf.to_container(hydra_cfg, enum_to_str=True)),
                ("overrides.yaml", overrides),
            ]
            writer = _Writer(folder, files)
            writer.start()
        with env_override(hydra_cfg.hydra.job.env_set):
            callbacks.on_job_start(config=config, task_function=task_function)
            try:
                ret.return_value = task_function(task_cfg)
                ret.status = JobStatus.COMPLETED
            except Exception as error:
                ret.return_value = error
                ret.status = JobStatus.FAILED
        ret.task_name = JobRuntime.instance().get("name")
        finishing, writer = writer, None
        if finishing is not None:
            finishing.finish()
        _flush_loggers()
        callbacks.on_job_end(config=config, job_return=ret)
        return ret
    finally:
        if writer is not None:
            writer.join()
        hydra.cfg = orig_hydra_cfg
        if chdir:
            os.chdir(old_cwd)
