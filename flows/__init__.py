"""Orchestration around the ``twostep`` library: no planning logic lives here.

===================  ==========================================================
module               what it is for
===================  ==========================================================
``cli``              the ``twostep`` Hydra app: one job, or a sweep with ``-m``
``config``           the structured config schema (typos fail at once)
``runner``           one job end to end: reuse or compute, files, MLflow
``job``              config -> library call (:func:`twostep.pipeline` methods)
``flow``             the Prefect flow of one job
``tasks``            the pipeline's steps as Prefect tasks (cache keys, retries)
``sweep``            the Hydra callback, shared sweep state, progress line
``server``           the sweep's Prefect server: on demand, watched, stopped by PID
``tracking``         MLflow: store check, experiments, parent/child runs (docs/tracking.md)
``store``            job keys and the store of finished jobs
``artifacts``        the files a job writes (and logs as artifacts)
``environment``      offline-safe environment defaults (telemetry off)
``llm``              the LLM decomposer built from the config
``report_cli``       ``twostep-report``: the paper's figures from the runs
===================  ==========================================================
"""
