"""PDDL domains and problems: reading, the in-memory model, and writing.

Files are parsed by unified-planning's ``PDDLReader``; the result is turned into the small,
immutable model (ground facts are tuples of lowercase names), which every other module
uses. Real-world files are read as they are: before unified-planning sees them, a light
s-expression pass reports unbalanced parentheses with file and line, and repairs the two
quirks of the LLM+P benchmark files (action names reused as predicate names, and domain
actions that mention objects only the problem declares).

One job per module:

- :mod:`twostep.pddl.model`    the model (facts, atoms, action schemas, domain, goal, problem)
- :mod:`twostep.pddl.errors`   :class:`PDDLError`, with file and line
- :mod:`twostep.pddl.sexp`     the s-expression reader and writer
- :mod:`twostep.pddl.repairs`  repairs of real-world quirks on s-expressions
- :mod:`twostep.pddl.adl`      ADL, action costs and ``either`` types compiled into the model
- :mod:`twostep.pddl.origins`  compiled plans in the task's own terms, and back
- :mod:`twostep.pddl.unified`  conversion from unified-planning's problem into the model
- :mod:`twostep.pddl.reader`   ``parse_problem``, ``load_problem``, ``parse_goal``
- :mod:`twostep.pddl.writer`   ``domain_to_pddl``, ``problem_to_pddl``

The model is STRIPS with typing, constants, negative preconditions and equality; ADL
(``exists``, ``forall``, ``or``, ``imply``, ``when``), ``:action-costs`` and ``either`` types, as
AlfWorld's ``alfred.pddl`` uses them, are compiled into it by :mod:`twostep.pddl.adl`.
"""

from twostep.pddl.errors import PDDLError
from twostep.pddl.model import (
    ActionOrigin,
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
from twostep.pddl.writer import domain_to_pddl, problem_to_pddl

__all__ = [
    "ActionOrigin",
    "ActionSchema",
    "Atom",
    "Domain",
    "Fact",
    "Goal",
    "PDDLError",
    "Problem",
    "SExp",
    "domain_to_pddl",
    "fact_to_pddl",
    "load_problem",
    "parse_goal",
    "parse_problem",
    "problem_to_pddl",
    "read_sexp",
    "write_sexp",
]
