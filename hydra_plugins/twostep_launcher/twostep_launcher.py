"""``hydra/launcher=twostep`` and ``hydra/sweeper=twostep`` (the defaults of ``twostep -m``).

Hydra finds plugins in the ``hydra_plugins`` package; the classes here only hand over to
:mod:`flows.launcher` (where and how the jobs run) and :mod:`flows.compose` (their configs),
imported when a sweep launches, so that Hydra's plugin scan stays cheap.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from hydra._internal.core_plugins.basic_sweeper import BasicSweeper
from hydra.core.utils import JobReturn
from hydra.plugins.launcher import Launcher
from hydra.types import HydraContext, TaskFunction
from omegaconf import DictConfig

if TYPE_CHECKING:
    from flows.compose import SweepComposer


class TwostepLauncher(Launcher):
    """Jobs on every core (``n_jobs`` worker processes, or a Dask cluster): see
    :mod:`flows.launcher`."""

    def __init__(
        self,
        n_jobs: int | None = None,
        backend: str = "processes",
        dask_address: str | None = None,
        **unused: Any,
    ) -> None:
        self.n_jobs = n_jobs
        self.backend = backend
        self.dask_address = dask_address
        self.config: DictConfig | None = None
        self.task_function: TaskFunction | None = None
        self.hydra_context: HydraContext | None = None
        self.composer: SweepComposer | None = None

    def setup(
        self, *, hydra_context: HydraContext, task_function: TaskFunction, config: DictConfig
    ) -> None:
        from flows.compose import SweepComposer

        self.config = config
        self.task_function = task_function
        self.hydra_context = hydra_context
        self.composer = SweepComposer(hydra_context.config_loader)

    def launch(
        self, job_overrides: Sequence[Sequence[str]], initial_job_idx: int
    ) -> Sequence[JobReturn]:
        from flows.launcher import launch

        assert self.config is not None and self.hydra_context is not None
        assert self.task_function is not None and self.composer is not None
        return launch(
            self.hydra_context,
            self.task_function,
            self.config,
            self.composer,
            job_overrides,
            initial_job_idx,
            n_jobs=self.n_jobs,
            backend=self.backend,
            dask_address=self.dask_address,
        )


class TwostepSweeper(BasicSweeper):
    """Hydra's basic sweeper (the same grid, order and batches), whose check of a batch
    before launching it derives each job's config from the first of its group set
    (:class:`flows.compose.SweepComposer`) instead of composing every job in full."""

    def setup(
        self, *, hydra_context: HydraContext, task_function: TaskFunction, config: DictConfig
    ) -> None:
        from flows.compose import SweepComposer

        super().setup(hydra_context=hydra_context, task_function=task_function, config=config)
        composer = getattr(self.launcher, "composer", None)
        self.composer = composer or SweepComposer(hydra_context.config_loader)

    def validate_batch_is_legal(self, batch: Sequence[Sequence[str]]) -> None:
        assert self.config is not None
        for overrides in batch:
            self.composer.validate(self.config, list(overrides))
