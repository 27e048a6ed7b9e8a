"""Tasks: the benchmark's tasks on disk in the LLM+P layout (:mod:`.benchmark`) and the
MA-PDDL compilation of a task for N agents (:mod:`.multiagent`)."""
