"""Skip conditions, declared once: inputs or programs a test needs that a machine may lack.

- :data:`needs_ipc_sample`: the IPC sample, ``<repo>/../shared/ipc-sample`` (:data:`IPC_SAMPLE`),
  an external test input that is not part of the repository;
- :data:`needs_alfworld`: the ``alfworld`` wheel's data (the ``embodied`` extra);
- :func:`skip_without_alfworld_engine`: AlfWorld's own engine (``make alfworld-engine``);
- :func:`skip_without_chromium`: a Chromium binary (``apt-get install -y chromium``), which
  it returns.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from checkers.trace_check import alfworld_layouts_folder
from tests.browser import chromium_binary

REPO = Path(__file__).resolve().parents[2]
IPC_SAMPLE = REPO.parent / "shared" / "ipc-sample"

needs_ipc_sample = pytest.mark.skipif(
    not IPC_SAMPLE.is_dir(), reason=f"the IPC sample is not at {IPC_SAMPLE} (external test input)"
)
needs_alfworld = pytest.mark.skipif(
    alfworld_layouts_folder() is None, reason="the alfworld wheel (extra 'embodied') is missing"
)


def skip_without_alfworld_engine() -> None:
    """Skip the calling test where AlfWorld's engine is not installed."""
    from checkers.alfworld_engine import engine_python

    if engine_python() is None:
        pytest.skip("AlfWorld's engine is not installed (make alfworld-engine)")


def skip_without_chromium() -> str:
    """The Chromium binary; the calling test is skipped where there is none."""
    binary = chromium_binary()
    if binary is None:
        pytest.skip("Chromium is not installed (apt-get install -y chromium)")
    return binary
