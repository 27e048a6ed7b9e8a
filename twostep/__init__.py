"""twostep: multi-agent task planning with classical planners and LLMs.

The library behind the ``twostep`` commands; importable without Prefect, MLflow or Hydra.
One module per step of the paper's pipeline:

- :mod:`twostep.pddl`         read domains and problems as Fast Downward does: the lifted
                              model, its grounding (Fast Downward's translator), writing
- :mod:`twostep.plans.simulate`       plans over the grounded model: lookup, simulation
- :mod:`twostep.planner`      Fast Downward (the up-fast-downward wheel's driver): named exit
                              codes, checked plan files, costs, statuses
- :mod:`twostep.verify.validation`   independent plan validation (unified-planning)
- :mod:`twostep.tasks.multiagent`   the MA-PDDL baseline compilation
- :mod:`twostep.plans.progression`  hand-off of the environment state between agents
- :mod:`twostep.makespan`    parallel execution length (A*) and joint schedule check
- :mod:`twostep.decomposers`  where helper subgoals come from (goal-split, plan-split,
                              expert, llm)
- :mod:`twostep.llm`          LLM access (litellm), prompts and answer parsing
- :mod:`twostep.methods`      the methods side by side (SA, MA, TwoStep, plan-deal,
                              portfolio), one request in, one result out; the registry
- :mod:`twostep.dealing`      plan-deal's algorithm: the SA plan's pieces dealt to N agents
- :mod:`twostep.tasks.benchmark`    tasks on disk in the LLM+P layout

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
