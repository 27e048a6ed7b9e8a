"""twostep's Hydra plugin: the sweeper of ``experiment=paper_replay`` (flows.replay_sweeper).

Hydra finds plugins only in the ``hydra_plugins`` namespace package; the sweeper's code is
:mod:`flows.replay_sweeper`, this class only gives it the name Hydra looks for.
"""

from flows.replay_sweeper import ReplaySweeperBase


class BundleSweeper(ReplaySweeperBase):
    """The jobs a replay bundle calls for (``hydra/sweeper=bundle``)."""


__all__ = ["BundleSweeper"]
