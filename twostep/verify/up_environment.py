"""unified-planning's environment, set up once for the project's files.

Reading PDDL needs only unified-planning's model and ``io`` packages, but its default
``Environment`` also builds the engine factory, whose import chain (ConfigSpace, scipy)
costs seconds per process. :func:`up_environment` installs, as unified-planning's global
environment, one that builds the factory on first use: a command that only reads PDDL
(``twostep-score``) never imports the engines; validating or solving through
unified-planning builds them as before.

Import this module only where unified-planning is needed (it imports its environment).
"""

from __future__ import annotations

from typing import Any

import unified_planning.environment
import unified_planning.model
import unified_planning.model.type_manager
import unified_planning.model.walkers
from unified_planning.environment import Environment


class LazyFactoryEnvironment(Environment):  # type: ignore[misc]
    """unified-planning's ``Environment`` whose engine factory is built when first asked."""

    def __init__(self) -> None:
        # Environment.__init__ without its ``Factory(self)``: the same attributes, in the
        # same order (unified-planning 1.3).
        model, walkers = unified_planning.model, unified_planning.model.walkers
        self._type_manager = model.type_manager.TypeManager()
        self._factory = None
        self._tc = walkers.TypeChecker(self)
        self._expression_manager = model.ExpressionManager(self)
        self._free_vars_oracle = model.FreeVarsOracle()
        self._simplifier = walkers.Simplifier(self)
        self._substituter = walkers.Substituter(self)
        self._free_vars_extractor = walkers.FreeVarsExtractor()
        self._names_extractor = walkers.NamesExtractor()
        self._credits_stream = None
        self._error_used_name = True

    @property
    def factory(self) -> Any:
        if self._factory is None:
            from unified_planning.engines import Factory

            self._factory = Factory(self)
        return self._factory


def up_environment() -> Any:
    """unified-planning's global environment (installed lazily, see above), set up for us."""
    env = unified_planning.environment.GLOBAL_ENVIRONMENT
    if env is None:
        env = unified_planning.environment.GLOBAL_ENVIRONMENT = LazyFactoryEnvironment()
    # LLM+P tyreworld names actions like predicates (open, close): allow it.
    env.error_used_name = False
    env.credits_stream = None
    return env
