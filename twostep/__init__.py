"""twostep: multi-agent task planning with classical planners and LLMs.

The library behind the ``twostep`` commands; importable without Prefect, MLflow or Hydra.
Every module sits in a package that names its job (tests/test_layout.py checks this map
against the packages):

- :mod:`twostep.pddl`         read domains and problems as Fast Downward does: the lifted
                              model, its grounding (Fast Downward's translator), writing
- :mod:`twostep.plans`        plans over the grounded model: lookup, simulation, the
                              hand-off between agents, the rules of helper subgoals
- :mod:`twostep.tasks`        tasks on disk in the LLM+P layout; the MA-PDDL compilation
- :mod:`twostep.generators`   seeded task generators per domain
- :mod:`twostep.programs`     Fast Downward's programs: where they live, the guard they run under
- :mod:`twostep.planner`      Fast Downward's driver: named exit codes, checked plan files,
                              costs, statuses
- :mod:`twostep.verify`       independent plan validation (unified-planning)
- :mod:`twostep.makespan`     scoring: parallel execution length (A*), joint schedule check
- :mod:`twostep.decomposers`  where helper subgoals come from (goal-split, plan-split,
                              expert, llm)
- :mod:`twostep.llm`          LLM access (litellm), prompts and answer parsing
- :mod:`twostep.english`      English subgoals into PDDL goals without a model (the rules translator)
- :mod:`twostep.replay`       real model answers from logs, replayed (import, bundle, check)
- :mod:`twostep.methods`      the methods side by side (SA, MA, TwoStep, plan-deal,
                              portfolio), one request in, one result out; the registry
- :mod:`twostep.dealing`      plan-deal's algorithm: the SA plan's pieces dealt to N agents
- :mod:`twostep.embodied`     the grid-kitchen executor and its pictures
- :mod:`twostep.report`       the report: run table, series, tables and figures
- :mod:`twostep.cli`          twostep-score, twostep-data, twostep-prompts
- :mod:`twostep.util`         the checked file reader and atomic writer; secrets masked;
                              the outcome vocabulary (every status enum and its sets)

Quick start::

    from twostep.tasks.benchmark import load_task
    from twostep.decomposers.goal_split import GoalSplitDecomposer
    from twostep.methods import MethodRequest, run_twostep
    from twostep.planner import PlannerSettings

    task = load_task("blocksworld", 5)
    agent_facts = ["arm-empty", "holding"]
    request = MethodRequest(task, agents=2, planner=PlannerSettings(),
                            agent_predicates=agent_facts,
                            decomposer=GoalSplitDecomposer(agent_facts))
    result = run_twostep(request)
    print(result.exec_length, result.schedule)
"""

import importlib
import sys
import warnings
from collections.abc import Sequence
from importlib import abc, machinery, metadata
from types import ModuleType

MOVED_MODULES = {
    "twostep.strips": "twostep.plans.simulate",
    "twostep.progression": "twostep.plans.progression",
    "twostep.subgoals": "twostep.plans.subgoals",
    "twostep.benchmark": "twostep.tasks.benchmark",
    "twostep.multiagent": "twostep.tasks.multiagent",
    "twostep.downward": "twostep.programs.downward",
    "twostep.processes": "twostep.programs.processes",
    "twostep.files": "twostep.util.files",
    "twostep.redaction": "twostep.util.redaction",
    "twostep.identity": "flows.identity",
    "twostep.params": "flows.tracking.params",
    "twostep.jobs.identity": "flows.identity",
    "twostep.replay.grid": "flows.replay_grid",  # the config's rules live in flows/
    "twostep.jobs.params": "flows.tracking.params",
    "twostep.jobs": "flows",  # (after its modules: the first name that matches wins)
    "twostep.validation": "twostep.verify.validation",
    "twostep.pddl.environment": "twostep.verify.up_environment",
    "twostep.pipeline": "twostep.methods",
    "twostep.execution": "twostep.makespan",  # and each of its modules
}
"""Old module name -> where it lives now (a package's modules moved with it): the old names
still import, with a DeprecationWarning, for one release."""

MOVED_NAMES = {
    "twostep.util.redaction.redact_config": "flows.redaction.redact_config",
    "twostep.report.load_runs_from_sweep_dir": "flows.report_sources.load_runs_from_sweep_dir",
    "twostep.report.runs.load_runs_from_sweep_dir": "flows.report_sources.load_runs_from_sweep_dir",
}
"""Old name of a function -> where it lives now: the config's rules moved to ``flows/``;
the old names still import (the module's ``__getattr__``), with the same warning."""


def _moved(name: str) -> str | None:
    """Where the module ``name`` lives now, if it moved."""
    for old, new in MOVED_MODULES.items():
        if name == old or name.startswith(f"{old}."):
            return new + name[len(old) :]
    return None


class _MovedModules(abc.MetaPathFinder, abc.Loader):
    """Imports a moved module's old name as the module it moved to."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> machinery.ModuleSpec | None:
        return machinery.ModuleSpec(fullname, self) if _moved(fullname) else None

    def create_module(self, spec: machinery.ModuleSpec) -> None:
        return None

    def exec_module(self, module: ModuleType) -> None:
        new = _moved(module.__name__)
        assert new is not None
        warnings.warn(
            f"{module.__name__} is now {new}; the old name goes in the next release",
            DeprecationWarning,
            stacklevel=2,
        )
        sys.modules[module.__name__] = importlib.import_module(new)


def moved_name(module: str, name: str, new_module: str) -> object:
    """``name`` of ``new_module``, for a module's ``__getattr__`` that still answers to a
    moved name (:data:`MOVED_NAMES`), with the moved modules' one-line warning."""
    warnings.warn(
        f"{module}.{name} is now {new_module}.{name}; the old name goes in the next release",
        DeprecationWarning,
        stacklevel=3,
    )
    return getattr(importlib.import_module(new_module), name)


sys.meta_path.insert(0, _MovedModules())  # before the path finder: one module per file

try:  # the installed version (from the git tag, pyproject's [tool.setuptools_scm])
    __version__ = metadata.version("twostep")
except metadata.PackageNotFoundError:  # a source tree that was never installed
    __version__ = "0.0.0+unknown"
