"""Real model answers recorded elsewhere, replayed through twostep's own pipeline.

The official TwoStep code logs, for every task and number of agents, the helper subgoals
its model proposed in English, each helper plan's cost, the single-agent cost and its own
multi-agent execution length. :mod:`twostep.replay.official` reads logs of that format
into a *replay bundle* (:mod:`twostep.replay.bundle`): per run, domain, task and N the
answers with their provenance (file and line, the model the user names) and the official
numbers (:mod:`twostep.replay.importer`, ``twostep-data import-answers``). The LLM client
answers the generate step from a bundle (``LLMSettings.mode="bundle"``:
:class:`twostep.llm.LLMClient`); :mod:`twostep.replay.check` checks how the model-free translator
(:mod:`twostep.english`) does against the helper costs the logs record (``twostep-data
check-answers``), and :mod:`flows.replay_grid` lists the jobs a bundle calls for
(the paper replay's sweep); :mod:`twostep.report.replay` draws Table I and Fig. 3.
"""

from twostep.replay.bundle import (
    BUNDLE_FILE,
    Answer,
    Bundle,
    BundleError,
    BundleMiss,
    Entry,
    OfficialNumbers,
    Run,
    load_bundle,
)

__all__ = [
    "BUNDLE_FILE",
    "Answer",
    "Bundle",
    "BundleError",
    "BundleMiss",
    "Entry",
    "OfficialNumbers",
    "Run",
    "load_bundle",
]
