"""The sweeper of ``experiment=paper_replay``: the jobs a replay bundle calls for.

Hydra's basic sweeper launches the product of its parameters; a bundle's grid is not a
product (SA once per task, TwoStep once per run of the bundle at each N, no job for a
task or N the logs do not answer). :class:`ReplaySweeperBase` (the Hydra plugin
``hydra_plugins.twostep_replay.BundleSweeper``, selected by ``hydra/sweeper=bundle``)
launches :func:`flows.replay_grid.replay_jobs` of the bundle named by ``llm.bundle``
instead. ``domain=``, ``task=``, ``agents=`` and ``seed=`` on the command line (one value
or a comma list) narrow the grid; every other override goes to every job;
``hydra.sweeper.methods`` picks the methods (default: sa, ma, twostep, plan-deal).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.errors import HydraException
from hydra.plugins.sweeper import Sweeper
from hydra.types import HydraContext, TaskFunction
from omegaconf import DictConfig, OmegaConf

FILTERS = ("domain", "task", "agents", "seed")


def expose_plugin() -> None:
    """Let Hydra find ``hydra_plugins.twostep_replay``: Hydra walks the folders of the
    ``hydra_plugins`` namespace, and an editable install (a checkout's ``make setup``)
    provides ours through an import hook that walk does not see; add its folder. An
    installed wheel has it in site-packages already: nothing to do."""
    import hydra_plugins

    folder = Path(__file__).resolve().parent.parent / "hydra_plugins"
    if (folder / "twostep_replay").is_dir() and str(folder) not in list(hydra_plugins.__path__):
        hydra_plugins.__path__.append(str(folder))


def _values(override: Any) -> list[str]:
    if override.is_sweep_override():
        return [str(v) for v in override.sweep_string_iterator()]
    return [str(override.get_value_element_as_str())]


def planned_jobs(config: DictConfig, arguments: list[str] | None = None) -> list[list[str]]:
    """Each job's overrides: the bundle's grid (narrowed by the filters), then the rest."""
    from flows.replay_grid import METHODS, replay_jobs
    from twostep.replay import BundleError, load_bundle

    arguments = list(config.hydra.overrides.task) if arguments is None else arguments
    parser = OverridesParser.create()
    filters: dict[str, list[str]] = {}
    passed: list[str] = []
    bundle_path = config.llm.get("bundle")
    for override in parser.parse_overrides(arguments):
        key = override.get_key_element()
        if key in FILTERS:
            filters[key] = _values(override)
        elif override.is_sweep_override():
            raise HydraException(
                f"{key}: experiment=paper_replay sweeps the bundle's grid; narrow it with "
                f"{', '.join(FILTERS)} (or hydra.sweeper.methods), not with a sweep of {key}"
            )
        elif key not in ("method", "decomposer"):
            passed.append(f"{key}={override.get_value_element_as_str()}")
    if not bundle_path:
        raise HydraException("experiment=paper_replay needs llm.bundle=<folder of a replay bundle>")
    try:
        bundle = load_bundle(Path(str(bundle_path)))
    except BundleError as error:
        raise HydraException(str(error)) from None
    methods = list(config.hydra.sweeper.get("methods") or METHODS)
    try:
        jobs = replay_jobs(
            bundle,
            str(config.llm.model),
            methods,
            domains=filters.get("domain"),
            tasks=[int(t) for t in filters["task"]] if "task" in filters else None,
            agents=[int(n) for n in filters["agents"]] if "agents" in filters else None,
            seeds=[int(s) for s in filters["seed"]] if "seed" in filters else None,
        )
    except ValueError as error:
        raise HydraException(str(error)) from None
    if not jobs:
        raise HydraException(
            f"{bundle_path}: no answers of {config.llm.model} for this grid "
            f"(models: {', '.join(bundle.models) or 'none'})"
        )
    return [[f"{k}={v}" for k, v in job.items()] + passed for job in jobs]


class ReplaySweeperBase(Sweeper):
    """Launches :func:`planned_jobs` (see the module docstring), ``max_batch_size`` at a
    time (None: all at once), as Hydra's basic sweeper launches its grid."""

    def __init__(
        self,
        max_batch_size: int | None = None,
        params: dict[str, str] | None = None,
        methods: list[str] | None = None,
    ) -> None:
        super().__init__()
        self.max_batch_size = max_batch_size
        self.methods = methods
        self.config: DictConfig | None = None
        self.hydra_context: HydraContext | None = None
        self.launcher: Any = None

    def setup(
        self, *, hydra_context: HydraContext, task_function: TaskFunction, config: DictConfig
    ) -> None:
        from hydra.core.plugins import Plugins

        self.config = config
        self.hydra_context = hydra_context
        self.launcher = Plugins.instance().instantiate_launcher(
            hydra_context=hydra_context, task_function=task_function, config=config
        )

    def sweep(self, arguments: list[str]) -> Any:
        assert self.config is not None and self.launcher is not None
        jobs = planned_jobs(self.config, arguments)
        size = self.max_batch_size if self.max_batch_size and self.max_batch_size > 0 else len(jobs)
        sweep_dir = Path(self.config.hydra.sweep.dir)
        sweep_dir.mkdir(parents=True, exist_ok=True)
        OmegaConf.save(self.config, sweep_dir / "multirun.yaml")
        # Composing every job's config before launching (as the basic sweeper does) took
        # about 5 minutes for the 944 jobs of the paper's logs here; the jobs of one kind
        # (domain, method, decomposer) differ only in typed numbers: one of each is composed.
        kinds: dict[tuple[str, ...], list[str]] = {}
        for job in jobs:
            kind = tuple(o for o in job if o.split("=", 1)[0] in ("domain", "method", "decomposer"))
            kinds.setdefault(kind, job)
        self.validate_batch_is_legal(list(kinds.values()))
        returns = []
        for first in range(0, len(jobs), size):
            batch = jobs[first : first + size]
            results = self.launcher.launch(batch, initial_job_idx=first)
            for result in results:
                _ = result.return_value  # a job that raised raises here
            returns.append(results)
        return returns
