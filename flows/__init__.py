"""Orchestration around the ``twostep`` library: no planning logic lives here.

===================  ==========================================================
module               what it is for
===================  ==========================================================
``cli``              the ``twostep`` Hydra app: one job, or a sweep with ``-m``
``config``           the structured config schema (typos fail at once)
``build``            config -> library objects: task, planner settings, decomposer
``runner``           one job end to end: reuse or compute, files, MLflow
``job``              config -> library call (:func:`twostep.methods.twostep` methods)
``flow``             the Prefect flow of one job
``tasks``            the pipeline's steps as Prefect tasks (cache keys, retries)
``sweep``            the Hydra callback of a sweep (start, summary, exit code)
``sweep_state``      what a sweep's jobs share on disk: state, identity, job records
``sweep_services``   the sweep's on-demand Prefect server and MLflow parent run
``progress``         the progress line, header and summary of a sweep
``server``           a Prefect server: started, watched, health, stopped by PID
``services``         ``twostep-services``: long-lived Prefect server and MLflow UI
``tracking``         MLflow: store check, experiments, parent/child runs (docs/tracking.md)
``tracking_worker``  a single run's MLflow logging in a process started with the job
``tracking_sqlite``  a single run's MLflow rows written into a warm SQLite store directly
``store``            the store of finished jobs (keys: :mod:`twostep.identity`)
``artifacts``        the files a job writes (and logs as artifacts)
``environment``      offline-safe environment defaults (telemetry off)
``llm``              the LLM decomposer built from the config
``report_cli``       ``twostep-report``: the paper's figures from the runs
===================  ==========================================================
"""
