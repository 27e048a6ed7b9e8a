"""PDDL domains and problems: reading, the lifted model, its grounding, and writing.

Files are read as Fast Downward reads them. Our own reader (:mod:`twostep.pddl.lifted`,
on :mod:`twostep.pddl.sexp`) gives the lifted model: what the files say, checked with
file and line. Fast Downward's translator, run as a program, grounds the task
(:mod:`twostep.pddl.translator`), and its output is read into the grounded model
(:mod:`twostep.pddl.grounded`): the states, actions with conditional effects, costs and
axioms every other module simulates. Real-world quirks are repaired on s-expressions
first (:mod:`twostep.pddl.repairs`).

One job per module:

- :mod:`twostep.pddl.model`       the lifted model (domain, action schemas, goal, problem)
- :mod:`twostep.pddl.grounded`    the grounded model: states, ground actions, axioms
- :mod:`twostep.pddl.errors`      :class:`PDDLError`, with file and line
- :mod:`twostep.pddl.sexp`        the s-expression reader and writer
- :mod:`twostep.pddl.lifted`      s-expressions to the lifted model, checked
- :mod:`twostep.pddl.lint`        types, arities and variables checked before Fast Downward
- :mod:`twostep.pddl.repairs`     repairs of real-world quirks on s-expressions
- :mod:`twostep.pddl.translator`  Fast Downward's translator, run as a bounded subprocess
- :mod:`twostep.pddl.sas`         its ``output.sas`` to the grounded model
- :mod:`twostep.pddl.goals`       quantified subgoals grounded by static facts
- :mod:`twostep.pddl.reader`      ``parse_problem``, ``load_problem`` (cached), ``parse_goal``
- :mod:`twostep.pddl.writer`      the PDDL the planner receives
"""

from twostep.pddl.errors import PDDLError
from twostep.pddl.grounded import GroundAction, GroundTask
from twostep.pddl.model import (
    ActionSchema,
    Atom,
    Domain,
    Fact,
    Goal,
    Problem,
    fact_to_pddl,
)
from twostep.pddl.reader import load_problem, parse_goal, parse_problem
from twostep.pddl.sexp import SExp, read_sexp, write_sexp
from twostep.pddl.writer import domain_to_pddl, planner_input, problem_to_pddl

__all__ = [
    "ActionSchema",
    "Atom",
    "Domain",
    "Fact",
    "Goal",
    "GroundAction",
    "GroundTask",
    "PDDLError",
    "Problem",
    "SExp",
    "domain_to_pddl",
    "fact_to_pddl",
    "load_problem",
    "parse_goal",
    "parse_problem",
    "planner_input",
    "problem_to_pddl",
    "read_sexp",
    "write_sexp",
]
