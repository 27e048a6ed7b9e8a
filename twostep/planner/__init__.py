"""Fast Downward, run from the driver that ships inside the ``up-fast-downward`` wheel.

One entry point, :func:`plan`, for every planner call of the project. It returns a
:class:`PlanResult`: the plan (the best complete one for anytime aliases), its cost, the
planner's own reported time, the wall time, and a :class:`Status`. A timeout, an
unsolvable task, an incomplete search or a crash is a status, never an exception.

One job per module, as in Fast Downward's ``driver/``:

- :mod:`twostep.planner.returncodes`  every exit code named, with its meaning
- :mod:`twostep.planner.aliases`      our alias names -> driver arguments
- :mod:`twostep.planner.plan_files`   plan files, trusted only with their cost trailer
- :mod:`twostep.planner.settings`     :class:`PlannerSettings` and the wall-clock guard
- :mod:`twostep.planner.results`      :class:`Status` and :class:`PlanResult`
- :mod:`twostep.planner.driver`       running the driver; :func:`plan`, :func:`plan_pddl`
"""

from twostep.pddl import planner_input
from twostep.planner.aliases import ALIASES, ANYTIME_ALIASES
from twostep.planner.driver import plan, plan_pddl, run_driver
from twostep.planner.plan_files import PlanFile, read_plan_file
from twostep.planner.results import PlanResult, Status
from twostep.planner.settings import WALL_GUARD_FACTOR, WALL_GUARD_OFFSET_S, PlannerSettings
from twostep.programs.downward import driver_path

__all__ = [
    "ALIASES",
    "ANYTIME_ALIASES",
    "WALL_GUARD_FACTOR",
    "WALL_GUARD_OFFSET_S",
    "PlanFile",
    "PlanResult",
    "PlannerSettings",
    "Status",
    "driver_path",
    "plan",
    "plan_pddl",
    "planner_input",
    "read_plan_file",
    "run_driver",
]
