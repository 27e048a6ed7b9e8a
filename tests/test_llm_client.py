"""The LLM client: cache, seeds, replay, scripted answers, retries and credentials.

No network: answers come from litellm's ``mock_response``, a ``litellm.CustomLLM``
provider registered by the test, or a patched ``litellm.completion``.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from twostep.llm import client as client_module
from twostep.llm.client import (
    LLMCacheCorrupt,
    LLMCacheMiss,
    LLMCallError,
    LLMClient,
    LLMCredentialsError,
    LLMScriptError,
    LLMSettings,
)

FAKE_KEY = "fake-test-key-DO-NOT-LEAK-0123456789"
MESSAGES = [{"role": "system", "content": "Be brief."}, {"role": "user", "content": "Goal?"}]


@pytest.fixture(scope="module")
def litellm() -> Any:
    return client_module._import_litellm()


@pytest.fixture
def settings(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> LLMSettings:
    monkeypatch.setenv("OPENAI_API_KEY", FAKE_KEY)
    return LLMSettings(
        cache_dir=tmp_path / "cache", backoff_s=0.001, extra={"mock_response": "(on-table b)"}
    )


@pytest.fixture
def no_network(litellm: Any, monkeypatch: pytest.MonkeyPatch) -> Iterator[list[dict[str, Any]]]:
    calls: list[dict[str, Any]] = []

    def refuse(**kwargs: Any) -> Any:
        calls.append(kwargs)
        raise AssertionError("litellm.completion must not be called")

    monkeypatch.setattr(litellm, "completion", refuse)
    yield calls


def test_import_does_not_load_litellm_and_sets_cost_map_flag() -> None:
    import os
    import subprocess
    import sys

    code = (
        "import sys, os; import twostep.llm, twostep.decomposers.llm; "
        "assert 'litellm' not in sys.modules; print(os.environ['LITELLM_LOCAL_MODEL_COST_MAP'])"
    )
    env = {k: v for k, v in os.environ.items() if k != "LITELLM_LOCAL_MODEL_COST_MAP"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "True"


def test_cache_hit_on_second_call(settings: LLMSettings, litellm: Any) -> None:
    client = LLMClient(settings)
    first = client.complete(MESSAGES, seed=0)
    assert (first.text, first.cached, first.scripted, first.model) == (
        "(on-table b)",
        False,
        False,
        "openai/gpt-4o",
    )
    second = client.complete(MESSAGES, seed=0)
    assert second.cached and second.text == first.text and second.key == first.key
    assert second.recorded_seconds == pytest.approx(first.seconds, abs=1e-6)
    entry = client.cache_path(first.key).read_text()
    assert FAKE_KEY not in entry and '"seed": 0' in entry


def test_seeds_are_distinct_cache_entries(settings: LLMSettings, litellm: Any) -> None:
    client = LLMClient(settings)
    keys = {client.complete(MESSAGES, seed=s).key for s in (0, 1, 2)}
    assert len(keys) == 3
    assert len(list(settings.cache_dir.rglob("*.json"))) == 3
    assert all(client.complete(MESSAGES, seed=s).cached for s in (0, 1, 2))


def test_key_covers_the_request_but_not_the_api_key(settings: LLMSettings) -> None:
    client = LLMClient(settings)
    base = client.cache_key(client.request(MESSAGES, 0))
    other_model = LLMClient(LLMSettings(model="openai/gpt-4o-mini", extra=settings.extra))
    assert other_model.cache_key(other_model.request(MESSAGES, 0)) != base
    hotter = LLMClient(LLMSettings(temperature=0.7, extra=settings.extra))
    assert hotter.cache_key(hotter.request(MESSAGES, 0)) != base
    keyed = LLMClient(LLMSettings(extra={**settings.extra, "api_key": FAKE_KEY}))
    request = keyed.request(MESSAGES, 0)
    assert keyed.cache_key(request) == base and FAKE_KEY not in str(request)


def test_replay_hit_needs_no_network(
    settings: LLMSettings, litellm: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    recorded = LLMClient(settings).complete(MESSAGES, seed=1)  # live, mock_response
    calls: list[Any] = []
    monkeypatch.setattr(litellm, "completion", lambda **kw: calls.append(kw))
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)  # replay needs no key either
    replay = LLMClient(
        LLMSettings(mode="replay", cache_dir=settings.cache_dir, extra=settings.extra)
    )
    answer = replay.complete(MESSAGES, seed=1)
    assert answer.cached and answer.text == recorded.text and not calls


def test_replay_miss_is_a_clear_error(settings: LLMSettings, no_network: list[Any]) -> None:
    replay = LLMClient(LLMSettings(mode="replay", cache_dir=settings.cache_dir))
    with pytest.raises(LLMCacheMiss) as info:
        replay.complete(MESSAGES, seed=2)
    message = str(info.value)
    assert "LLMSettings.mode=replay" in message and "seed 2" in message and "Goal?" in message
    assert "openai/gpt-4o" in message and "LLMSettings.mode=live" in message
    assert not no_network and not settings.cache_dir.exists()


def test_scripted_answers_in_order(tmp_path: Path, no_network: list[Any]) -> None:
    script = tmp_path / "answers.yaml"
    script.write_text("answers:\n  - first\n  - |\n    (:goal (and (clear a)))\n")
    client = LLMClient(LLMSettings(mode="scripted", script=script, cache_dir=tmp_path / "c"))
    one, two = client.complete(MESSAGES, 0), client.complete(MESSAGES, 0)
    assert (one.text, two.text.strip()) == ("first", "(:goal (and (clear a)))")
    assert one.scripted and two.scripted and not one.cached
    assert one.model == "scripted"
    with pytest.raises(LLMScriptError, match="has 2 answer"):
        client.complete(MESSAGES, 0)
    assert not (tmp_path / "c").exists() and not no_network


def test_scripted_needs_a_valid_script(tmp_path: Path) -> None:
    with pytest.raises(LLMScriptError, match=r"needs LLMSettings\.script"):
        LLMClient(LLMSettings(mode="scripted"))
    bad = tmp_path / "bad.yaml"
    bad.write_text("answer: oops\n")
    with pytest.raises(LLMScriptError, match="needs a list 'answers:'"):
        LLMClient(LLMSettings(mode="scripted", script=bad))
    assert LLMClient(LLMSettings(mode="scripted"), answers=["x"]).complete(MESSAGES, 0).text == "x"


def test_unknown_mode() -> None:
    with pytest.raises(Exception, match=r"LLMSettings\.mode must be one of live, replay, scripted"):
        LLMSettings(mode="offline")


def test_retries_rate_limit_then_succeeds(
    settings: LLMSettings, litellm: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    real = litellm.completion
    calls: list[dict[str, Any]] = []

    def flaky(**kwargs: Any) -> Any:
        calls.append(kwargs)
        if len(calls) == 1:
            raise litellm.RateLimitError("slow down", llm_provider="openai", model="gpt-4o")
        if len(calls) == 2:
            raise litellm.Timeout("timed out", model="gpt-4o", llm_provider="openai")
        return real(**kwargs)

    monkeypatch.setattr(litellm, "completion", flaky)
    answer = LLMClient(settings).complete(MESSAGES, seed=0)
    assert answer.text == "(on-table b)" and len(calls) == 3
    assert calls[0]["seed"] == 0 and calls[0]["temperature"] == 0.0 and calls[0]["top_p"] == 1.0
    assert calls[0]["api_key"] == FAKE_KEY and calls[0]["max_retries"] == 0


def test_gives_up_after_max_retries(
    settings: LLMSettings, litellm: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[int] = []

    def down(**kwargs: Any) -> Any:
        calls.append(1)
        raise litellm.InternalServerError(f"boom {FAKE_KEY}", llm_provider="openai", model="x")

    monkeypatch.setattr(litellm, "completion", down)
    settings.max_retries = 2
    with pytest.raises(LLMCallError, match="after 3 attempts") as info:
        LLMClient(settings).complete(MESSAGES, seed=0)
    assert len(calls) == 3 and FAKE_KEY not in str(info.value)


def test_no_retry_on_bad_request(
    settings: LLMSettings, litellm: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[int] = []

    def bad(**kwargs: Any) -> Any:
        calls.append(1)
        raise litellm.BadRequestError("max_tokens too large", model="gpt-4o", llm_provider="openai")

    monkeypatch.setattr(litellm, "completion", bad)
    with pytest.raises(LLMCallError, match="BadRequestError"):
        LLMClient(settings).complete(MESSAGES, seed=0)
    assert len(calls) == 1


def test_auth_error_is_one_line_naming_the_variable(
    settings: LLMSettings, litellm: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[int] = []

    def denied(**kwargs: Any) -> Any:
        calls.append(1)
        raise litellm.AuthenticationError(
            f"Incorrect API key provided: {FAKE_KEY}", llm_provider="openai", model="gpt-4o"
        )

    monkeypatch.setattr(litellm, "completion", denied)
    with pytest.raises(LLMCredentialsError) as info:
        LLMClient(settings).complete(MESSAGES, seed=0)
    message = str(info.value)
    assert len(calls) == 1 and "\n" not in message and FAKE_KEY not in message
    assert "OPENAI_API_KEY" in message
    assert "GoalSplitDecomposer" in message and "LLMSettings.mode=replay" in message
    assert info.value.__cause__ is None and info.value.__suppress_context__


@pytest.mark.parametrize(
    "model, variable",
    [
        ("openai/gpt-4o", "OPENAI_API_KEY"),
        ("anthropic/claude-3-5-sonnet-latest", "ANTHROPIC_API_KEY"),
    ],
)
def test_missing_key_fails_before_any_call(
    model: str,
    variable: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    no_network: list[Any],
) -> None:
    monkeypatch.delenv(variable, raising=False)
    client = LLMClient(LLMSettings(model=model, cache_dir=tmp_path))
    with pytest.raises(LLMCredentialsError, match=variable):
        client.complete(MESSAGES, seed=0)
    assert not no_network


def test_self_hosted_servers_need_no_key(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)
    assert LLMSettings(model="openai/qwen", api_base="http://127.0.0.1:8000/v1").key_env is None
    assert LLMSettings(model="ollama/llama3.1", api_base="http://127.0.0.1:11434").key_env is None
    assert LLMSettings(api_key_env="MY_GATEWAY_KEY").key_env == "MY_GATEWAY_KEY"


def test_custom_provider_through_the_real_litellm_path(
    tmp_path: Path, litellm: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A litellm.CustomLLM provider: the request goes through litellm's routing."""
    seen: list[dict[str, Any]] = []

    class Echo(litellm.CustomLLM):  # type: ignore[misc]
        def completion(self, *args: Any, **kwargs: Any) -> Any:
            seen.append(kwargs)
            if len(seen) == 1:
                raise litellm.RateLimitError("busy", llm_provider="echo", model="echo")
            last = kwargs["messages"][-1]["content"]
            return litellm.completion(
                model="openai/gpt-4o", messages=kwargs["messages"], mock_response=f"echo: {last}"
            )

    monkeypatch.setattr(
        litellm, "custom_provider_map", [{"provider": "echo", "custom_handler": Echo()}]
    )
    settings = LLMSettings(model="echo/v1", cache_dir=tmp_path, backoff_s=0.001)
    answer = LLMClient(settings).complete(MESSAGES, seed=3)
    assert answer.text == "echo: Goal?" and not answer.cached and len(seen) == 2
    assert LLMClient(settings).complete(MESSAGES, seed=3).cached


@pytest.mark.parametrize(
    "damage",
    [
        lambda text: text[: len(text) // 2],  # truncated mid-write (before atomic writes)
        lambda text: "",  # an empty file
        lambda text: '{"key": "k", "request": {}}',  # valid JSON without the answer
    ],
    ids=["truncated", "empty", "no-answer"],
)
def test_corrupt_cache_entry_is_reported_and_fetched_again_live(
    settings: LLMSettings,
    litellm: Any,
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
    damage: Any,
) -> None:
    client = LLMClient(settings)
    first = client.complete(MESSAGES, seed=0)
    path = client.cache_path(first.key)
    path.write_text(damage(path.read_text()))
    real = litellm.completion
    calls: list[int] = []

    def counted(**kwargs: Any) -> Any:
        calls.append(1)
        return real(**kwargs)

    monkeypatch.setattr(litellm, "completion", counted)
    with caplog.at_level("WARNING", logger="twostep.llm.client"):
        again = client.complete(MESSAGES, seed=0)
    assert not again.cached and again.text == first.text and calls == [1]
    [warning] = [r for r in caplog.records if r.levelname == "WARNING"]
    assert str(path) in warning.getMessage() and "corrupt" in warning.getMessage()
    # the entry was written again: the next call is a hit, with no warning
    caplog.clear()
    assert client.complete(MESSAGES, seed=0).cached and calls == [1]
    assert not caplog.records


def test_corrupt_cache_entry_fails_a_replay_naming_the_file(
    settings: LLMSettings, litellm: Any, no_network: list[Any]
) -> None:
    replay = LLMClient(replace(settings, mode="replay"))
    path = replay.cache_path(replay.cache_key(replay.request(MESSAGES, 0)))
    path.parent.mkdir(parents=True)
    path.write_text('{"key": "x", "text": "(on-tab')  # an entry cut off mid-write
    with pytest.raises(LLMCacheCorrupt) as info:
        replay.complete(MESSAGES, seed=0)
    assert str(path) in str(info.value) and "LLMSettings.mode=live" in str(info.value)
    assert not no_network


# ----------------------------------------------------------------- issue 20: 3, 5, 7

CHARGE = """
import json, sys, time
import twostep.llm.client as client_module
from twostep.llm.client import LLMClient, LLMSettings

class Clock:  # the client's clock; importing litellm is made to last 1000 s on it
    offset = 0.0
    def __getattr__(self, name):
        return getattr(time, name)
    def perf_counter(self):
        return time.perf_counter() + self.offset

clock = Clock()
client_module.time = clock
real_import = client_module._import_litellm
def slow_import(*args, **kwargs):
    if client_module._litellm is None:  # importing it now (later: the module it holds)
        clock.offset += 1000.0
    return real_import(*args, **kwargs)
client_module._import_litellm = slow_import

loaded = []  # per call: the modules there when its HTTP call starts, and those it imports
live = LLMClient._call_live
def watched(self, *args, **kwargs):
    before = set(sys.modules)
    try:
        return live(self, *args, **kwargs)
    finally:
        loaded.append([sorted(before), sorted(set(sys.modules) - before)])
LLMClient._call_live = watched

assert "litellm" not in sys.modules
settings = LLMSettings(model="openai/standin", api_base=sys.argv[1], use_cache=False,
                       max_retries=0, timeout_s=30)
client = LLMClient(settings)
messages = [{"role": "user", "content": "Goal?"}]
seconds = [client.complete(messages, seed).seconds for seed in (0, 1)]
print(json.dumps({"seconds": seconds, "loaded": loaded,
                  "warmed": list(client_module._FIRST_CALL_MODULES)}))
"""


def test_first_and_second_call_of_a_process_are_charged_alike() -> None:
    """Before: the first live call of every process was charged litellm's import (5-8 s of
    `generate` against 0.02 s of `translate`), in llm_time_s and so planning_time_s. Two
    calls through a stand-in server on 127.0.0.1, in a fresh process whose client clock
    makes the import last 1000 s: neither call is charged it; and litellm and the modules
    of its first real call are loaded before the first call's HTTP part (in its clock)
    starts, so that part imports none of them. No machine's speed is assumed."""
    import json
    import subprocess
    import sys

    from tests.llm_standin import standin_server

    with standin_server(["(on-table b)", "(on-table c)"]) as server:
        done = subprocess.run(
            [sys.executable, "-c", CHARGE, server.api_base],
            capture_output=True,
            text=True,
            timeout=240,
        )
    assert done.returncode == 0, done.stderr[-2000:]
    facts = json.loads(done.stdout.splitlines()[-1])
    assert len(server.requests) == 2  # both were live calls
    first, second = facts["seconds"]
    assert 0 < first < 1000 and 0 < second < 1000, (first, second)  # the import: not charged
    (before, imported), _ = facts["loaded"]
    for module in ["litellm", *facts["warmed"]]:
        assert module in before and module not in imported, module
    assert not [m for m in imported if m.split(".")[0] in {"openai", "httpx", "httpcore"}]


def test_rejected_credentials_name_the_real_cause(tmp_path: Path) -> None:
    """Before: an HTTP 401 read `LLM credentials missing ... set the environment variable
    the API key variable of provider 'openai'` (wrong cause, garbled)."""
    from tests.llm_standin import Fault, standin_server

    with standin_server([Fault(status=401)]) as server:
        settings = LLMSettings(
            model="openai/standin", api_base=server.api_base, cache_dir=tmp_path, max_retries=0
        )
        with pytest.raises(LLMCredentialsError) as info:
            LLMClient(settings).complete(MESSAGES, seed=0)
    message = str(info.value)
    assert message.startswith(f"LLM credentials rejected by {server.api_base} (HTTP 401)")
    assert "LLMSettings.api_key_env=<VARIABLE>" in message
    assert "the API key variable of" not in message
    assert "missing" not in message


@pytest.mark.parametrize(
    "value", ["sk-proj-9Qx2", "sk-ant-api03-Zz", "x" * 10 + "-y", "aB3dEfGh1234567890XyZw"]
)
def test_a_key_given_as_the_variable_name_is_refused_without_echoing_it(value: str) -> None:
    with pytest.raises(client_module.LLMError) as info:
        LLMSettings(api_key_env=value)
    assert value not in str(info.value)
    assert str(info.value).startswith(
        "LLMSettings.api_key_env looks like a key, not a variable name"
    )
    for name in ("OPENAI_API_KEY", "my_gateway_key", "TWOSTEP_TEST_CANARY_KEY"):
        assert LLMSettings(api_key_env=name).key_env == name


def test_url_credentials_stay_out_of_the_cache(tmp_path: Path, litellm: Any) -> None:
    """The request as it is cached names the server without its user and password."""
    settings = LLMSettings(
        model="openai/x", api_base="https://user:pa55word@llm.example.org/v1", cache_dir=tmp_path
    )
    request = LLMClient(settings).request(MESSAGES, seed=0)
    assert request["api_base"] == "https://***@llm.example.org/v1"


def test_litellm_lines_are_printed_once_and_info_only_when_asked() -> None:
    """Issue 39, finding 13: each LiteLLM INFO line was printed twice (its own handler and
    the application's root handler), for the warm-up call too."""
    import logging

    from twostep.llm import client

    client._import_litellm()
    logger = logging.getLogger("LiteLLM")
    seen: list[logging.LogRecord] = []
    root_handler = logging.Handler()
    root_handler.emit = seen.append  # type: ignore[method-assign]
    root = logging.getLogger()
    root.addHandler(root_handler)
    try:
        logger.info("LiteLLM completion() model= gpt-4o; provider = openai")
        logger.warning("a warning")
    finally:
        root.removeHandler(root_handler)
    assert seen == []  # nothing reaches the application's (root) handlers
    assert not logger.isEnabledFor(logging.INFO) and logger.isEnabledFor(logging.WARNING)
