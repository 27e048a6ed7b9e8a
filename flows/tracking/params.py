"""Run parameters as flat, dotted names: ``{"planner": {"alias": "lama"}}`` -> ``planner.alias``.

One definition for both sides of a report: the MLflow writer (:mod:`flows.tracking.contents`)
logs params under these names and the sweep-dir reader (:mod:`flows.report_sources`)
rebuilds them from the jobs' ``.hydra/config.yaml``, so both sources group runs the same
way. Kept free of heavy imports: every job loads it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any


def flatten_config(config: Mapping[str, Any], prefix: str = "") -> dict[str, str]:
    """A nested config as ``{"a.b.c": "value"}`` with every leaf as a string."""
    flat: dict[str, str] = {}
    for key, value in config.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            flat.update(flatten_config(value, f"{name}."))
        else:
            flat[name] = "None" if value is None else str(value)
    return flat
