"""Where Fast Downward lives: the copy inside the installed ``up-fast-downward`` wheel.

Found without importing the package: its ``__init__`` imports unified-planning's engines
(ConfigSpace, scipy), seconds per process that neither the driver nor the translator
needs. Fast Downward is GPL-3: the project runs it as a program (the driver for search,
the translator for grounding) and never imports its code.
"""

from __future__ import annotations

import functools
import importlib.util
from pathlib import Path


@functools.cache
def downward_dir() -> Path:
    """The ``downward`` folder of the wheel (driver script, builds, translator)."""
    spec = importlib.util.find_spec("up_fast_downward")
    if spec is None or not spec.submodule_search_locations:
        raise FileNotFoundError("up-fast-downward is not installed")
    return Path(next(iter(spec.submodule_search_locations))).resolve() / "downward"


def driver_path() -> Path:
    """Fast Downward's driver script, ``fast-downward.py``."""
    return downward_dir() / "fast-downward.py"


def translator_path() -> Path:
    """The folder to put on ``PYTHONPATH`` to run ``python -m fast_downward.translate``."""
    return downward_dir() / "builds" / "release" / "bin"
