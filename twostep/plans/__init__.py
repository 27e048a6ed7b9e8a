"""Plans over the grounded model: simulation and action lookup (:mod:`.simulate`), the
hand-off of the environment state between agents (:mod:`.progression`), and the rules a
helper subgoal must pass (:mod:`.subgoals`)."""
