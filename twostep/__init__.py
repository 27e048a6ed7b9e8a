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
- :mod:`twostep.execution`    parallel execution length (A*) and joint schedule check
- :mod:`twostep.decomposers`  where helper subgoals come from (goal-split, plan-split,
                              expert, llm)
- :mod:`twostep.llm`          LLM access (litellm), prompts and answer parsing
- :mod:`twostep.methods`      the methods side by side (SA, MA, TwoStep, plan-deal,
                              portfolio), one request in, one result out; the registry
- :mod:`twostep.dealing`      plan-deal's algorithm: the SA plan's pieces dealt to N agents
- :mod:`twostep.embodied`     the grid-kitchen executor and its pictures
- :mod:`twostep.jobs`         a job's identity (key, name, input files) and flat params
- :mod:`twostep.report`       the report: run table, series, tables and figures
- :mod:`twostep.cli`          twostep-score, twostep-data, twostep-prompts
- :mod:`twostep.util`         the checked file reader and atomic writer; secrets masked

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

from importlib import metadata

try:  # the installed version (from the git tag, pyproject's [tool.setuptools_scm])
    __version__ = metadata.version("twostep")
except metadata.PackageNotFoundError:  # a source tree that was never installed
    __version__ = "0.0.0+unknown"
