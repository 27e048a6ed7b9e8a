"""The LLM decomposer end to end with scripted answers: good ones and each bad kind.

Every answer here is written by the test (``mode="scripted"``); none comes from a model.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from tests.support.data import make_blocksworld_data
from twostep.decomposers.base import Decomposer, DecompositionRequest, SubgoalProposal
from twostep.decomposers.llm import NONE_REASON, LLMDecomposer, generate_subgoal, translate_subgoal
from twostep.llm.client import (
    LLMCacheMiss,
    LLMCallError,
    LLMClient,
    LLMResponse,
    LLMScriptError,
    LLMSettings,
)
from twostep.llm.client import Message as ClientMessage
from twostep.tasks.benchmark import BenchmarkTask, load_task

# task p01: b on c, a and c on the table; goal (on a b) (on c a)
GEN_B = (
    "It can put b on the table. Therefore, agent1's complete and final goal condition is: "
    "b is on the table and the arm is empty."
)
GEN_C = "agent2's final goal condition is: c is clear and the arm is empty."
PDDL_B = "```pddl\n(:goal (and (on-table b) (arm-empty)))\n```"
PDDL_C = "(:goal (and (clear c) (arm-empty)))"


@pytest.fixture(scope="module")
def task(tmp_path_factory: pytest.TempPathFactory) -> BenchmarkTask:
    return load_task("blocksworld", 1, make_blocksworld_data(tmp_path_factory.mktemp("data")))


def scripted(*answers: str) -> LLMClient:
    return LLMClient(LLMSettings(mode="scripted"), answers=list(answers))


def run(task: BenchmarkTask, agents: int, *answers: str) -> list[SubgoalProposal]:
    decomposer: Decomposer = LLMDecomposer(scripted(*answers))
    return decomposer.propose(DecompositionRequest(task, agents, seed=0))


def statuses(proposals: list[SubgoalProposal]) -> list[tuple[int, str, str | None]]:
    return [(p.helper, p.status, p.reason) for p in proposals]


def test_good_answers_for_two_helpers(task: BenchmarkTask) -> None:
    client = scripted(GEN_B, PDDL_B, GEN_C, PDDL_C)
    result = LLMDecomposer(client).decompose(DecompositionRequest(task, 3, seed=2))
    first, second = result.proposals
    assert (first.status, first.english, first.pddl) == (
        "proposed",
        "b is on the table and the arm is empty",
        "(and (arm-empty) (on-table b))",
    )
    assert (second.status, second.pddl) == ("proposed", "(and (arm-empty) (clear c))")
    assert result.stopped_at is None and result.error is None
    generate, translate = first.exchanges
    assert [m["role"] for m in generate["messages"]] == ["system", "user", "assistant"]
    assert generate["messages"][-1]["text"] == GEN_B and translate["messages"][-1]["text"] == PDDL_B
    assert all(x["scripted"] and not x["cached"] and x["seed"] == 2 for x in (generate, translate))
    assert first.llm_time_s == pytest.approx(generate["seconds"] + translate["seconds"])
    # the second helper's prompt lists the first helper's subgoal
    prompt = second.exchanges[0]["messages"][1]["text"]
    assert "agent1: b is on the table and the arm is empty" in prompt
    assert "b is on the table and the arm is empty" in translate["messages"][1]["text"]
    assert first.to_dict()["exchanges"] == first.exchanges


def test_none_for_the_first_helper_gives_no_proposals(task: BenchmarkTask) -> None:
    result = LLMDecomposer(scripted("None.")).decompose(DecompositionRequest(task, 3))
    assert result.stopped_at == 1
    assert result.stop_exchange is not None and result.stop_exchange["status"] == "none"
    # the answer is kept (for result.json) as a stopped proposal, nothing to plan
    [stop] = result.proposals
    assert (stop.helper, stop.status, stop.pddl) == (1, "stopped", None)
    assert stop.exchanges == [result.stop_exchange]


def test_none_stops_later_helpers(task: BenchmarkTask) -> None:
    proposals = run(task, 4, GEN_B, PDDL_B, "none")
    assert statuses(proposals) == [(1, "proposed", None), (2, "stopped", NONE_REASON)]


def test_more_answers_than_helpers_are_ignored(task: BenchmarkTask) -> None:
    client = scripted(GEN_B, PDDL_B, GEN_C, PDDL_C, GEN_C)
    proposals = LLMDecomposer(client).propose(DecompositionRequest(task, 2))
    assert statuses(proposals) == [(1, "proposed", None)]


def test_answer_for_several_helpers_takes_the_asked_one(task: BenchmarkTask) -> None:
    both = GEN_B + "\n" + GEN_C
    proposals = run(task, 3, both, PDDL_B, both, PDDL_C)
    assert [p.english for p in proposals] == [
        "b is on the table and the arm is empty",
        "c is clear and the arm is empty",
    ]


@pytest.mark.parametrize(
    "answers, reason",
    [
        (("",), "empty answer from the subgoal generator"),
        (("Helpers should cooperate to finish quickly!",), "no final goal condition"),
        ((GEN_B, ""), "empty answer from the translator"),
        ((GEN_B, "Sorry, I cannot write PDDL."), "no PDDL goal in the translator's answer"),
        ((GEN_B, "(:goal (and on-table b))"), "invalid PDDL subgoal: not a ground literal"),
        (
            (GEN_B, "(:goal (and (on-floor b)))"),
            "invalid PDDL subgoal: unknown predicate 'on-floor'",
        ),
        ((GEN_B, "(:goal (and (on-table d)))"), "invalid PDDL subgoal: unknown object 'd'"),
        ((GEN_B, "(:goal (on b))"), "invalid PDDL subgoal: 'on' takes 2 argument(s), got 1"),
        ((GEN_B, "(:goal (and (on c a) (on a b)))"), "equals the full goal"),
        ((GEN_B, "(:goal (and (not (on a b)) (arm-empty)))"), "contradicts the main goal"),
    ],
)
def test_bad_answers_are_discarded_with_the_reason(
    task: BenchmarkTask, answers: tuple[str, ...], reason: str
) -> None:
    (proposal,) = run(task, 2, *answers)
    assert proposal.status == "discarded"
    assert proposal.reason is not None and proposal.reason.startswith(reason)
    assert proposal.exchanges and proposal.exchanges[-1]["reason"] == proposal.reason
    raw = [x["messages"][-1]["text"] for x in proposal.exchanges]
    assert raw == list(answers)  # every raw answer is kept


def test_discard_then_continue_and_repeats(task: BenchmarkTask) -> None:
    proposals = run(task, 4, "", GEN_B, PDDL_B, GEN_B, PDDL_B)
    assert statuses(proposals) == [
        (1, "discarded", "empty answer from the subgoal generator"),
        (2, "proposed", None),
        (3, "discarded", "repeats the subgoal of agent2"),
    ]


def test_steps_as_separate_functions(task: BenchmarkTask) -> None:
    client = scripted(GEN_B, PDDL_C, "none")
    english, gen = generate_subgoal(client, task, 3, 1, [], seed=1)
    assert english == "b is on the table and the arm is empty" and gen["status"] == "ok"
    pddl, tr = translate_subgoal(client, task, english, seed=1, helper=1)
    assert pddl == "(and (arm-empty) (clear c))" and tr["parsed"] == pddl
    assert (tr["step"], tr["helper"], tr["status"]) == ("translate", 1, "ok")
    english, gen = generate_subgoal(client, task, 3, 2, ["x"], seed=1)
    assert english is None and gen["status"] == "none"


class FailingClient(LLMClient):
    def complete(self, messages: list[ClientMessage], seed: int) -> LLMResponse:  # type: ignore[override]
        raise LLMCallError("LLM call to openai/gpt-4o failed after 5 attempts: RateLimitError")


def test_failed_call_discards_and_stops(task: BenchmarkTask) -> None:
    decomposer = LLMDecomposer(FailingClient(LLMSettings()))
    result = decomposer.decompose(DecompositionRequest(task, 3))
    assert statuses(result.proposals) == [
        (
            1,
            "discarded",
            "LLM call failed: LLM call to openai/gpt-4o failed after 5 attempts: RateLimitError",
        )
    ]
    assert result.error is not None and result.error.startswith("generate for agent1")


def test_script_running_out_is_an_error(task: BenchmarkTask) -> None:
    with pytest.raises(LLMScriptError, match="used up"):
        run(task, 2, GEN_B)


def test_pipeline_falls_back_to_single_agent(task: BenchmarkTask, tmp_path: Path) -> None:
    """Through the pipeline with scripted answers: helper accepted / all discarded."""
    pipeline = pytest.importorskip("twostep.methods")
    from twostep.planner import PlannerSettings

    settings = PlannerSettings(search_time_limit_s=20)
    good = pipeline.run_twostep(
        pipeline.MethodRequest(
            task, 2, settings, ["arm-empty", "holding"], LLMDecomposer(scripted(GEN_B, PDDL_B))
        )
    )
    assert good.success and good.scripted_llm
    assert [s["status"] for s in good.subgoals] == ["accepted"]
    assert good.schedule and {agent for step in good.schedule for agent, _ in step} == {
        "agent0",
        "agent1",
    }
    bad = pipeline.run_twostep(
        pipeline.MethodRequest(
            task,
            2,
            settings,
            ["arm-empty", "holding"],
            LLMDecomposer(scripted(GEN_B, "(:goal (and (on-floor b)))")),
        )
    )
    assert bad.success and bad.fallback == "no helper subgoal accepted"
    assert [s["status"] for s in bad.subgoals] == ["discarded"]


def test_replay_reproduces_a_recorded_decomposition(
    task: BenchmarkTask, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Recorded in live mode (answers from mock_response), replayed with no network."""
    from twostep.llm.client import _import_litellm

    litellm = _import_litellm()
    real = litellm.completion

    def answer(**kwargs: object) -> object:
        user = str(kwargs["messages"][1]["content"])  # type: ignore[index]
        reply = PDDL_B if "The new goal in PDDL" in user else GEN_B
        return real(**kwargs, mock_response=reply)

    monkeypatch.setenv("OPENAI_API_KEY", "sk-test-not-a-key")
    monkeypatch.setattr(litellm, "completion", answer)
    settings = LLMSettings(cache_dir=tmp_path / "cache")
    request = DecompositionRequest(task, 2, seed=1)
    live = LLMDecomposer(LLMClient(settings)).propose(request)
    monkeypatch.setattr(litellm, "completion", None)  # any call now fails
    monkeypatch.delenv("OPENAI_API_KEY")
    replay = LLMDecomposer(LLMClient(replace(settings, mode="replay"))).propose(request)

    def strip(proposals: list[SubgoalProposal]) -> list[dict[str, object]]:
        out = []
        for p in proposals:
            d = p.to_dict()
            d.pop("llm_time_s")
            d["exchanges"] = [
                {k: v for k, v in x.items() if k not in ("seconds", "recorded_seconds", "cached")}
                for x in d["exchanges"]
            ]
            out.append(d)
        return out

    assert live[0].status == "proposed" and not live[0].exchanges[0]["cached"]
    assert all(x["cached"] for x in replay[0].exchanges)
    assert strip(replay) == strip(live)
    other_seed = DecompositionRequest(task, 2, seed=2)
    with pytest.raises(LLMCacheMiss, match="seed 2"):
        LLMDecomposer(LLMClient(replace(settings, mode="replay"))).propose(other_seed)


def test_failed_call_makes_propose_raise_llm_error(task: BenchmarkTask) -> None:
    from twostep.decomposers.base import DecomposerError

    with pytest.raises(DecomposerError) as info:
        LLMDecomposer(FailingClient(LLMSettings())).propose(DecompositionRequest(task, 3))
    assert info.value.status == "llm_error"
    assert str(info.value).startswith("LLM call failed: generate for agent1")
    assert [p.helper for p in info.value.proposals] == [1]
