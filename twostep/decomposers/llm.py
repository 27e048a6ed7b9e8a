"""The paper's decomposer: an LLM proposes and translates one subgoal per helper.

For helpers 1..N-1: :func:`generate_subgoal` asks for the helper's English subgoal (the
answer "none" ends the loop), :func:`translate_subgoal` turns it into a PDDL goal and
checks it against the task (:mod:`twostep.plans.subgoals`, the rules that need no state). With
``LLMSettings.translator="rules"`` the translation is the model-free grammar's
(:mod:`twostep.english`): a sentence it cannot read is a discarded proposal whose reason
starts with :data:`TRANSLATION_FAILED`. Answers replayed from a bundle
(``LLMSettings.mode="bundle"``) carry their source (model, file, line) in the exchange.
Every prompt and raw answer is kept in the proposal's ``exchanges``; an answer that
gives no usable subgoal becomes a ``discarded`` proposal with the reason.

A call that fails (:class:`~twostep.llm.client.LLMCallError`: the client's retries are
spent, or credentials are missing) is no answer at all: :meth:`LLMDecomposer.propose`
raises :class:`~twostep.decomposers.base.DecomposerError` with status ``llm_error``, and
the run fails instead of falling back to the single-agent plan.

The two steps are plain functions; :meth:`LLMDecomposer.decompose` calls the ones the
request names (:attr:`~twostep.decomposers.base.DecompositionRequest.generate` and
``translate``: the TwoStep method passes :attr:`twostep.methods.steps.Steps.generate` and
``translate``), so a workflow engine can run each call as its own task.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from twostep.decomposers.base import (
    DecomposerError,
    DecompositionRequest,
    Exchange,
    LLMStep,
    SubgoalProposal,
)
from twostep.llm.client import LLMCallError, LLMClient, LLMResponse
from twostep.llm.parsing import parse_english_subgoal, parse_pddl_subgoal
from twostep.llm.prompts import Message, generator_messages, translator_messages
from twostep.pddl import parse_goal
from twostep.plans.subgoals import SubgoalError, SubgoalStatus, goal_conflict
from twostep.tasks.benchmark import BenchmarkTask
from twostep.util.outcome import ExchangeStatus, RunStatus

# The run status of a decomposition whose LLM call failed (result.json ``status``).
LLM_ERROR = RunStatus.LLM_ERROR.value
# How the reason of a subgoal the rules translator could not read begins.
TRANSLATION_FAILED = "translation failed"


def _exchange(
    step: str, helper: int, seed: int, messages: Sequence[Message], response: LLMResponse
) -> Exchange:
    """One prompt and its raw answer, as recorded in result.json."""
    return {
        "step": step,
        "helper": helper,
        "seed": seed,
        "model": response.model,
        "cached": response.cached,
        "scripted": response.scripted,
        "seconds": round(response.seconds, 6),
        "recorded_seconds": round(response.recorded_seconds, 6),
        "messages": [{"role": m["role"], "text": m["content"]} for m in messages]
        + [{"role": "assistant", "text": response.text}],
        "status": ExchangeStatus.OK.value,
        "reason": None,
        "parsed": None,
        "note": None,
        **({"source": response.source} if response.source else {}),
    }


def _ask(
    client: LLMClient, messages: Sequence[Message], seed: int, about: dict[str, object]
) -> LLMResponse:
    """One call; ``about`` (what it is for) goes along where the answers come from a
    replay bundle, which finds them by it."""
    if client.settings.mode == "bundle":
        return client.complete(messages, seed, about)
    return client.complete(messages, seed)


def _about(step: str, task: BenchmarkTask, agents: int, helper: int) -> dict[str, object]:
    return {
        "step": step,
        "domain": task.domain_name,
        "task": task.task_id,
        "agents": agents,
        "helper": helper,
    }


def generate_subgoal(
    client: LLMClient,
    task: BenchmarkTask,
    agents: int,
    helper: int,
    earlier: Sequence[str],
    seed: int,
    *,
    fixed_example: bool = True,
) -> tuple[str | None, Exchange]:
    """Ask for helper ``helper``'s English subgoal.

    Returns the final goal condition, or None; then ``exchange["status"]`` is ``"none"``
    (the LLM says no further helper helps: stop) or ``"discarded"`` (``"reason"`` says why).
    """
    messages = generator_messages(task, agents, helper, earlier, fixed_example=fixed_example)
    response = _ask(client, messages, seed, _about("generate", task, agents, helper))
    exchange = _exchange("generate", helper, seed, messages, response)
    try:
        parsed = parse_english_subgoal(response.text, helper, task.problem)
    except SubgoalError as exc:
        exchange.update(status=ExchangeStatus.DISCARDED.value, reason=str(exc))
        return None, exchange
    if parsed.kind == "none":
        exchange.update(
            status=ExchangeStatus.NONE.value, reason="the LLM answered that no further helper helps"
        )
        return None, exchange
    exchange.update(parsed=parsed.text, note=parsed.note)
    return parsed.text, exchange


def translate_subgoal(
    client: LLMClient,
    task: BenchmarkTask,
    english: str,
    seed: int,
    *,
    helper: int = 1,
    earlier: Mapping[int, str] | None = None,
    agents: int | None = None,
) -> tuple[str | None, Exchange]:
    """Translate ``english`` into a PDDL goal checked against the task: by the model, or
    by the rules (``client.settings.translator``).

    Returns the goal as canonical PDDL text (``(and ...)``), or None with
    ``exchange["status"] == "discarded"`` and the reason. ``earlier`` maps earlier
    helpers to their PDDL subgoals, to reject repeats; ``agents`` is the task's N (a
    replay bundle that logs the model's translations finds them by it).
    """
    problem = task.problem
    if client.settings.translator == "rules":
        exchange = _translate_by_rules(task, english, seed, helper)
        if exchange["status"] != ExchangeStatus.OK:
            return None, exchange
        text = str(exchange["parsed"])
    else:
        messages = translator_messages(task, english)
        about = _about("translate", task, agents or helper + 1, helper)
        response = _ask(client, messages, seed, about)
        exchange = _exchange("translate", helper, seed, messages, response)
        text = response.text
    try:
        goal = parse_pddl_subgoal(text, problem)
    except SubgoalError as exc:
        exchange.update(status=ExchangeStatus.DISCARDED.value, reason=str(exc))
        return None, exchange
    others = {h: parse_goal(text, problem) for h, text in (earlier or {}).items()}
    reason = goal_conflict(goal, problem.goal, others)
    exchange["parsed"] = goal.to_pddl()
    if reason is not None:
        exchange.update(status=ExchangeStatus.DISCARDED.value, reason=reason)
        return None, exchange
    return goal.to_pddl(), exchange


def _translate_by_rules(task: BenchmarkTask, english: str, seed: int, helper: int) -> Exchange:
    """The rules translator's reading of ``english``, as a translate exchange."""
    from twostep.english import translate_english

    start = time.perf_counter()
    translation = translate_english(task.problem, english, task.domain_name)
    exchange: Exchange = {
        "step": "translate",
        "helper": helper,
        "seed": seed,
        "model": "rules",
        "translator": "rules",
        "cached": False,
        "scripted": False,
        "seconds": round(time.perf_counter() - start, 6),
        "recorded_seconds": 0.0,
        "messages": [
            {"role": "user", "text": english},
            {"role": "assistant", "text": translation.pddl or ""},
        ],
        "status": ExchangeStatus.OK.value,
        "reason": None,
        "parsed": translation.pddl,
        "note": "; ".join(translation.notes) or None,
    }
    if translation.pddl is None:
        exchange.update(
            status=ExchangeStatus.DISCARDED.value,
            reason=f"{TRANSLATION_FAILED}: {translation.reason}",
        )
    return exchange


@dataclass
class LLMDecomposition:
    """Everything one decomposition produced, including a stopping "none" answer."""

    proposals: list[SubgoalProposal]
    stopped_at: int | None = None  # the helper for which the LLM answered "none"
    stop_exchange: Exchange | None = None
    error: str | None = None  # an LLM call that failed after retries: the loop stopped
    exchanges: list[Exchange] = field(default_factory=list)

    def fail(self, helper: int, step: str, error: Exception, done: list[Exchange]) -> None:
        """Record a call that failed after its retries (``done``: the exchanges before it)."""
        self.error = f"{step} for agent{helper}: {error}"
        self.proposals.append(
            SubgoalProposal(
                helper,
                None,
                None,
                SubgoalStatus.DISCARDED,
                f"LLM call failed: {error}",
                _seconds(*done),
                done,
            )
        )


def _seconds(*exchanges: Exchange) -> float:
    return float(sum(e["seconds"] for e in exchanges))


NONE_REASON = "the LLM answered none: no further helper"


class LLMDecomposer:
    """TwoStep's LLM decomposer (the subgoal source named ``llm``): generate, translate, check."""

    name = "llm"

    def __init__(self, client: LLMClient, *, fixed_example: bool = True) -> None:
        self.client = client
        self.fixed_example = fixed_example

    @property
    def _replays_translations(self) -> bool:
        """A bundle answers the translate step too: it needs the task's N to find them."""
        settings = self.client.settings
        return settings.mode == "bundle" and settings.translator == "llm"

    def propose(self, request: DecompositionRequest) -> list[SubgoalProposal]:
        """The proposals; :class:`DecomposerError` (``llm_error``) when a call failed."""
        result = self.decompose(request)
        if result.error is not None:
            raise DecomposerError(f"LLM call failed: {result.error}", LLM_ERROR, result.proposals)
        return result.proposals

    def decompose(self, request: DecompositionRequest) -> LLMDecomposition:
        """Generate and translate a subgoal per helper with the request's step functions."""
        task, seed = request.task, request.seed
        generate: LLMStep = request.generate or generate_subgoal
        translate: LLMStep = request.translate or translate_subgoal
        result = LLMDecomposition(proposals=[])
        english_so_far: list[str] = []
        accepted: dict[int, str] = {}
        for helper in range(1, request.agents):
            try:
                english, gen = generate(
                    self.client, task, request.agents, helper, english_so_far, seed,
                    fixed_example=self.fixed_example,
                )  # fmt: skip
            except LLMCallError as exc:
                result.fail(helper, "generate", exc, [])
                break
            result.exchanges.append(gen)
            if gen["status"] == ExchangeStatus.NONE:
                result.stopped_at, result.stop_exchange = helper, gen
                # kept as a proposal so that result.json records the answer
                result.proposals.append(
                    SubgoalProposal(
                        helper, None, None, SubgoalStatus.STOPPED, NONE_REASON, _seconds(gen), [gen]
                    )
                )
                break
            if english is None:
                result.proposals.append(
                    SubgoalProposal(
                        helper,
                        None,
                        None,
                        SubgoalStatus.DISCARDED,
                        gen["reason"],
                        _seconds(gen),
                        [gen],
                    )
                )
                continue
            english_so_far.append(english)
            try:
                pddl, tr = translate(
                    self.client, task, english, seed, helper=helper, earlier=accepted,
                    **({"agents": request.agents} if self._replays_translations else {}),
                )  # fmt: skip
            except LLMCallError as exc:
                result.fail(helper, "translate", exc, [gen])  # the answer given before it
                break
            result.exchanges.append(tr)
            if pddl is not None:
                accepted[helper] = pddl
            result.proposals.append(_translated(helper, english, pddl, gen, tr))
        return result


def _translated(
    helper: int, english: str, pddl: str | None, gen: Exchange, tr: Exchange
) -> SubgoalProposal:
    """The proposal of a translated subgoal: proposed, or discarded with the reason."""
    if pddl is not None:
        return SubgoalProposal(
            helper, pddl, english, SubgoalStatus.PROPOSED, None, _seconds(gen, tr), [gen, tr]
        )
    return SubgoalProposal(
        helper, tr["parsed"], english, SubgoalStatus.DISCARDED, tr["reason"],
        _seconds(gen, tr), [gen, tr],
    )  # fmt: skip


__all__ = [
    "LLM_ERROR",
    "TRANSLATION_FAILED",
    "Exchange",
    "LLMDecomposer",
    "LLMDecomposition",
    "generate_subgoal",
    "translate_subgoal",
]
