"""The jobs a replay bundle calls for (``experiment=paper_replay``), as each job's
overrides: :func:`replay_jobs` (the replay sweeper, :mod:`flows.replay_sweeper`, launches them).

For every (domain, task, N) the bundle answers with the chosen model:

* ``twostep``: TwoStep on the replayed answers (``decomposer=llm``), one job per run of
  the bundle for that domain and N (the seed picks the run: the paper's runs are seeds);
* ``plan-deal``: twostep's own method (``method=plan-deal``) on the same task and N
  (deterministic: seed 0);
* ``ma``: multi-agent planning at that N (seed 0);
* ``sa``: single-agent planning, once per (domain, task) (N plays no part in it).

Jobs are listed task by task, so that a sweep stopped early has whole tasks done.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

from twostep.replay.bundle import Bundle, same_model

METHODS = ("sa", "ma", "twostep", "plan-deal")


def replay_jobs(
    bundle: Bundle,
    model: str,
    methods: Sequence[str] = METHODS,
    *,
    domains: Collection[str] | None = None,
    tasks: Collection[int] | None = None,
    agents: Collection[int] | None = None,
    seeds: Collection[int] | None = None,
) -> list[dict[str, str]]:
    """Each job's overrides (``domain``, ``task``, ``agents``, ``method``, ``seed`` and,
    for TwoStep, ``decomposer``), restricted to the given domains, tasks, N and seeds."""
    unknown = [m for m in methods if m not in METHODS]
    if unknown:
        raise ValueError(
            f"unknown replay method(s) {', '.join(unknown)} (known: {', '.join(METHODS)})"
        )
    runs = {r.id for r in bundle.runs if same_model(model, r.model)}
    cells = sorted(
        {
            e.key
            for e in bundle.entries
            if e.run in runs
            and (domains is None or e.domain in domains)
            and (tasks is None or e.task in tasks)
            and (agents is None or e.agents in agents)
        }
    )

    def keep_seed(seed: int) -> bool:
        return seeds is None or seed in seeds

    jobs: list[dict[str, str]] = []
    by_task: dict[tuple[str, int], list[int]] = {}
    for domain, task, n in cells:
        by_task.setdefault((domain, task), []).append(n)
    for (domain, task), ns in by_task.items():
        base = {"domain": domain, "task": str(task)}
        if "sa" in methods and keep_seed(0):
            jobs.append({**base, "method": "sa", "agents": str(min(ns)), "seed": "0"})
        for n in ns:
            cell = {**base, "agents": str(n)}
            if "ma" in methods and keep_seed(0):
                jobs.append({**cell, "method": "ma", "seed": "0"})
            if "twostep" in methods:
                for seed, run in enumerate(bundle.runs_for(domain, n, model)):
                    if keep_seed(seed) and bundle.has(run.id, domain, task, n):
                        jobs.append(
                            {**cell, "method": "twostep", "decomposer": "llm", "seed": str(seed)}
                        )
            if "plan-deal" in methods and keep_seed(0):
                jobs.append({**cell, "method": "plan-deal", "seed": "0"})
    return jobs
