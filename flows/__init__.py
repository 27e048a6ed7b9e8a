"""Orchestration around the ``twostep`` library: no planning logic lives here.

==================  ==========================================================
module              what it is for
==================  ==========================================================
``cli``             the ``twostep`` Hydra app: one job, or a sweep with ``-m``
``config``          the structured config schema (typos fail at once)
``checks``          checks before any work: config values, writable locations
``build``           config -> library objects, once per job (:class:`~flows.build.Job`)
``job``             one job end to end: reuse or compute, files, MLflow record
``status``          how a job ended, from its result (tags, records, flow state)
``step_stats``      what a job's step calls did: fresh calls, cache hits, time
``prefect_flow``    the Prefect flow of one job and its tasks (cache keys, retries)
``identity``        job identity: which keys count, the key, names, storing
``store``           the store of finished jobs (keys: :mod:`flows.identity`)
``artifacts``       the files a job writes (and logs as artifacts)
``console``         what the commands print: summary, schedule, progress, one-line errors
``wording``         the library's messages with the config keys (one table of names)
``sweep_callback``  the Hydra callback of a sweep (start, summary, exit code)
``sweep_state``     what a sweep's jobs share on disk: state, identity, job records
``sweep_report``    the sweep's report, drawn in a process of its own at its end
``sweep_timing``    the sweep's timing line (wall, planner, the rest's share)
``launcher``        the default launcher of a sweep: every core, or a Dask cluster
``compose``         a sweep's job configs, composed once per set of group choices
``run_job``         one job the way Hydra's ``run_job`` runs it, with fewer copies
``servers``         Prefect servers we start: spawned, watched, shared by a sweep, stopped
``prefect_template`` the empty Prefect database every new Prefect home copies
``services``        ``twostep-services``: long-lived Prefect server and MLflow UI
``tracking``        MLflow: one interface (:mod:`flows.tracking.runs`), its writers
``redaction``       a config's secrets masked (the ``*_env`` rule)
``locations``       the local files and folders behind URIs; whether they can be written
``environment``     offline-safe environment defaults (telemetry off)
``report_cli``      ``twostep-report``: the paper's figures from the runs
``report_sources``  a report's runs: key columns, sweep dirs, what params mean
==================  ==========================================================
"""
