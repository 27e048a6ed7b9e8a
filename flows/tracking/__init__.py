"""MLflow tracking, as docs/tracking.md lays it out; the rest of ``flows/`` calls only
:mod:`flows.tracking.runs` (this package imports nothing itself, so that its helper process
and its template maker start light).

==============  ================================================================
module          what it is for
==============  ================================================================
``runs``        the interface: :class:`JobRunLog` (a job's run), :func:`end_sweep_run`
``contents``    what a run holds: params, metrics, tags, the record of one job
``context``     the system tags (user, source, git commit) MLflow's providers would set
``client``      MLflow's own client (:class:`~flows.tracking.client.Tracker`), the store check
``worker``      a single run's logging in a helper process that imports MLflow meanwhile
``template``    the environment's empty store, made by MLflow, copied for every new store
==============  ================================================================
"""
