"""Process environment for Prefect, MLflow and litellm on machines without internet.

These variables are read when the libraries are imported, so they are set before any
of them is (``flows.cli`` calls :func:`quiet_defaults` first). Values a user exported
win: only missing ones are set. STACK-NOTES explains each one.
"""

from __future__ import annotations

import os

DEFAULTS = {
    # MLflow looks up telemetry endpoints at import and at every run.
    "MLFLOW_DISABLE_TELEMETRY": "true",
    # Stops the MLflow server's job runner importing litellm (it hangs offline).
    "MLFLOW_SERVER_ENABLE_JOB_EXECUTION": "false",
    # litellm downloads a model cost map at import unless told to use its local copy.
    "LITELLM_LOCAL_MODEL_COST_MAP": "True",
    # The Prefect server sends usage analytics and logs errors when it cannot.
    "PREFECT_SERVER_ANALYTICS_ENABLED": "false",
    "DO_NOT_TRACK": "1",
}


def quiet_defaults() -> None:
    """Set the offline-safe defaults above for this process and its children."""
    for name, value in DEFAULTS.items():
        os.environ.setdefault(name, value)
