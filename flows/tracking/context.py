"""Where and by whom a run was made: the system tags MLflow's own run-context providers
set (``mlflow.user``, ``mlflow.source.name``, ``mlflow.source.type``,
``mlflow.source.git.commit``), computed here without importing MLflow (a job's record is
made before MLflow is loaded, and every writer logs the same tags), plus
``twostep.git_dirty`` (tracked files changed since that commit).

The commit is the one of the checkout twostep runs from (:func:`flows.console.git_state`);
an installed wheel has none, and its runs carry no git tags.
"""

from __future__ import annotations

import getpass
import sys
from functools import cache

from flows.console import git_state

USER = "mlflow.user"
SOURCE_NAME = "mlflow.source.name"
SOURCE_TYPE = "mlflow.source.type"
GIT_COMMIT = "mlflow.source.git.commit"
GIT_DIRTY = "twostep.git_dirty"


@cache
def run_context_tags() -> dict[str, str]:
    """The system tags of every run this process logs (computed once per process)."""
    try:
        user = getpass.getuser()
    except (KeyError, OSError):  # no name for this uid (some containers)
        user = "unknown"
    tags = {USER: user, SOURCE_NAME: sys.argv[0] or "python", SOURCE_TYPE: "LOCAL"}
    state = git_state()
    if state is not None:
        tags[GIT_COMMIT], dirty = state
        tags[GIT_DIRTY] = "true" if dirty else "false"
    return tags
