"""The one LLM client of the project: every call goes through ``litellm.completion``.

:class:`LLMClient` adds what a reproducible experiment needs on top of litellm:

* a disk cache keyed by a hash of the whole request (model, messages, temperature, top_p,
  max_tokens, seed, api_base, extra parameters; never the API key), one JSON file per
  request under ``cache_dir``, so a re-run needs no network; the run's seed is part of
  the request, so seeds 0, 1, 2 are three distinct calls;
* ``mode="replay"``: answers only from the cache and raises :class:`LLMCacheMiss` on a miss;
* a cache entry that cannot be read back (truncated, not JSON, no answer text) is corrupt,
  never a silent miss: a live call warns naming the file and asks the model again (the
  new answer replaces the entry); a replay raises :class:`LLMCacheCorrupt` naming it;
* ``mode="scripted"``: answers from a YAML script (``answers:`` list, in call order),
  marked ``scripted`` and never written to the cache;
* ``mode="bundle"``: answers recorded elsewhere by a real model, from a replay bundle
  (``bundle``: :mod:`twostep.replay`), looked up by what the call is about (the task, N,
  helper and step the decomposer names) and the seed (which of the bundle's runs); the
  request is built, keyed and logged as for a live call, the answer carries its source
  (model, file, line) and is never written to the cache; a call the bundle cannot answer
  raises :class:`LLMBundleMiss`;
* ``translator``: ``llm`` (the paper's: the model translates) or ``rules`` (the
  model-free grammar of :mod:`twostep.english`; the translate step then calls no model);
* the one retry loop of the project for LLM calls: exponential backoff (``backoff_s``,
  doubling, ``max_retries`` retries) on rate limits, timeouts, connection errors and 5xx,
  none on authentication or bad requests; what still fails is an :class:`LLMCallError`;
* missing or rejected credentials become a one-line :class:`LLMCredentialsError` (an
  :class:`LLMCallError`) naming the variable to set and the offline alternatives. No key
  is ever printed, logged or stored.

litellm is imported lazily on the first live call (it takes seconds to import); the
import is not counted in the call's time (:attr:`LLMResponse.seconds`).
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib
import json
import logging
import os
import re
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from twostep.util.files import FileFormatError, NotTextError, read_yaml_file, write_json_atomic
from twostep.util.redaction import holds_a_key, looks_like_a_key, redact_text

os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")

MODES = ("live", "replay", "scripted", "bundle")
TRANSLATORS = ("llm", "rules")
CACHE_FORMAT = 1
OFFLINE_HINT = "or run offline with GoalSplitDecomposer or LLMSettings.mode=replay (cached answers)"

# Environment variable that litellm reads for each provider prefix.
PROVIDER_KEY_ENV = {
    "openai": "OPENAI_API_KEY",
    "anthropic": "ANTHROPIC_API_KEY",
    "gemini": "GEMINI_API_KEY",
    "mistral": "MISTRAL_API_KEY",
    "groq": "GROQ_API_KEY",
    "deepseek": "DEEPSEEK_API_KEY",
    "openrouter": "OPENROUTER_API_KEY",
    "together_ai": "TOGETHERAI_API_KEY",
    "cohere": "COHERE_API_KEY",
}
_SECRET_PARAM = re.compile(r"key|secret|password|authorization|headers", re.IGNORECASE)

Message = Mapping[str, str]

log = logging.getLogger(__name__)

_litellm: Any = None  # the lazily imported litellm module

# What litellm's first real call would import on its own (hundreds of modules, about half
# a second): the OpenAI SDK's chat resources and types, which it uses for OpenAI and
# OpenAI-compatible servers, and the HTTP stack.
_FIRST_CALL_MODULES = ("openai.resources.chat", "httpcore", "h11")


def _import_litellm(model: str = "openai/warm-up") -> Any:
    """litellm, imported once per process and warmed up, so that no call's time holds
    an import: a completion answered by litellm's own ``mock_response`` (no network)
    walks its routing for ``model``, and the modules of its first real call are loaded."""
    global _litellm
    if _litellm is None:
        os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
        import litellm

        litellm.suppress_debug_info = True
        with contextlib.suppress(Exception):  # a model litellm cannot route: no warm-up
            litellm.completion(
                model=model, messages=[{"role": "user", "content": "-"}], mock_response="-"
            )
        for name in _FIRST_CALL_MODULES:
            with contextlib.suppress(ImportError):
                importlib.import_module(name)
        _litellm = litellm
    _quiet_litellm_logs()  # again on each use: litellm may set its loggers up anew
    return _litellm


LITELLM_LOGGERS = ("LiteLLM", "LiteLLM Router", "LiteLLM Proxy")


def _quiet_litellm_logs() -> None:
    """litellm's log lines once, by its own handler (they also reached the root logger's
    handler of the application: every line twice), and only its warnings unless
    ``LITELLM_LOG`` asks for more (its INFO lines say "completion() model=..." for the
    warm-up call too, which is not a call to the model)."""
    for name in LITELLM_LOGGERS:
        logger = logging.getLogger(name)
        logger.propagate = False
        if "LITELLM_LOG" not in os.environ:
            logger.setLevel(logging.WARNING)


class LLMError(Exception):
    """An LLM call that could not produce an answer."""


class LLMCallError(LLMError):
    """The provider failed (after retries, or with an error that is not worth retrying)."""


class LLMCredentialsError(LLMCallError):
    """No usable API key: the message names the variable to set (never the key)."""


class LLMCacheMiss(LLMError):
    """``mode="replay"`` and the request is not in the cache."""


class LLMCacheCorrupt(LLMError):
    """``mode="replay"`` and the request's cache entry cannot be read back."""


class LLMScriptError(LLMError):
    """The scripted answers are missing, malformed or used up."""


class LLMBundleMiss(LLMError):
    """``mode="bundle"`` and the bundle holds no answer for the call (or cannot be read)."""


@dataclass
class LLMSettings:
    """How to reach the model and how to cache, replay or script its answers."""

    model: str = "openai/gpt-4o"
    temperature: float = 0.0
    top_p: float | None = 1.0
    max_tokens: int = 512
    api_base: str | None = None
    api_key_env: str | None = None  # env var holding the key (default: the provider's)
    mode: str = "live"  # live | replay | scripted
    cache_dir: Path = Path("outputs/llm-cache")
    script: Path | None = None  # YAML file with `answers:` (mode=scripted)
    max_retries: int = 4
    backoff_s: float = 1.0
    timeout_s: float = 60.0
    use_cache: bool = True
    local: bool = False  # serve `model` from the in-process llama.cpp server
    bundle: Path | None = None  # a replay bundle's folder (mode=bundle)
    translator: str = "llm"  # llm | rules: who turns English subgoals into PDDL
    extra: dict[str, Any] = field(default_factory=dict)  # more litellm.completion kwargs

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise LLMError(f"LLMSettings.mode must be one of {', '.join(MODES)}, got '{self.mode}'")
        if self.translator not in TRANSLATORS:
            raise LLMError(
                f"LLMSettings.translator must be one of {', '.join(TRANSLATORS)}, got '{self.translator}'"
            )
        if self.mode == "bundle" and self.bundle is None:
            raise LLMError(
                "LLMSettings.mode=bundle needs LLMSettings.bundle=<folder of a replay bundle>"
            )
        if self.bundle is not None:
            self.bundle = Path(self.bundle)
        problem = key_env_problem(self.api_key_env)
        if problem:
            raise LLMError(problem)
        self.cache_dir = Path(self.cache_dir)
        if self.script is not None:
            self.script = Path(self.script)

    @property
    def provider(self) -> str:
        if "/" in self.model:
            return self.model.split("/", 1)[0]
        if self.model.startswith("claude"):
            return "anthropic"
        return "openai" if self.model.startswith(("gpt-", "o1", "o3", "o4")) else ""

    @property
    def key_env(self) -> str | None:
        """The environment variable that must hold the API key, if one is needed."""
        if self.api_key_env:
            return self.api_key_env
        if self.api_base or self.local:
            return None  # a self-hosted OpenAI-compatible server or Ollama: no key
        return PROVIDER_KEY_ENV.get(self.provider)


@dataclass(frozen=True)
class LLMResponse:
    """One answer; ``seconds`` is this call's wall time, ``recorded_seconds`` the live call's."""

    text: str
    cached: bool
    scripted: bool
    model: str
    seconds: float
    recorded_seconds: float = 0.0
    key: str = ""
    source: dict[str, Any] | None = None  # a replayed answer: model, run, file, line


def key_env_problem(name: str | None) -> str | None:
    """Why ``name`` cannot be :attr:`LLMSettings.api_key_env` (None: it can). The value is never
    repeated: it may be a key pasted where the variable's name belongs."""
    if name is None or not looks_like_a_key(name):
        return None
    return (
        "LLMSettings.api_key_env looks like a key, not a variable name: give the name of the "
        "environment variable that holds the key (e.g. LLMSettings.api_key_env=OPENAI_API_KEY); "
        "the value is not shown"
    )


def model_problem(model: str | None) -> str | None:
    """Why ``model`` cannot be :attr:`LLMSettings.model` (None: it can): it holds something shaped
    like a key (:func:`~twostep.util.redaction.holds_a_key`). The value is never repeated."""
    if model is None or not holds_a_key(model):
        return None
    return (
        "LLMSettings.model looks like it holds a key: give the model's name only "
        "(e.g. LLMSettings.model=openai/gpt-4o) and the key in the environment variable "
        "named by LLMSettings.api_key_env; the value is not shown"
    )


def credentials_message(settings: LLMSettings) -> str:
    """No key to send: which variable to set (or how to name one), and the offline ways."""
    where = f"for model {settings.model}"
    if settings.key_env:
        return (
            f"LLM credentials missing {where}: set the environment variable "
            f"{settings.key_env}, {OFFLINE_HINT}."
        )
    return (
        f"LLM credentials missing {where}: no API key variable is known for provider "
        f"'{settings.provider or 'unknown'}'; put the key in an environment variable and "
        f"name it with LLMSettings.api_key_env=<VARIABLE>, {OFFLINE_HINT}."
    )


def rejected_message(settings: LLMSettings, status: int | None) -> str:
    """The provider refused the credentials it got (HTTP 401/403): which key, and where."""
    server = (
        redact_text(settings.api_base) if settings.api_base else f"provider '{settings.provider}'"
    )
    code = f" (HTTP {status})" if status else ""
    if settings.key_env:
        sent = f"the key in the environment variable {settings.key_env}"
        fix = "check that key"
    else:
        placeholder = (settings.api_base or settings.local) and settings.provider == "openai"
        sent = "a placeholder key (no key variable is set)" if placeholder else "no API key"
        fix = (
            "if it needs a key, name the variable that holds it with "
            "LLMSettings.api_key_env=<VARIABLE>"
        )
    return (
        f"LLM credentials rejected by {server}{code} for model {settings.model}: "
        f"it was sent {sent}; {fix}, {OFFLINE_HINT}."
    )


def load_script(path: Path) -> list[str]:
    """Read the ``answers:`` list of a script file."""

    try:
        data = read_yaml_file(Path(path))
    except (NotTextError, FileFormatError) as exc:
        raise LLMScriptError(f"cannot read LLM script: {exc}") from None
    except OSError as exc:
        raise LLMScriptError(f"cannot read LLM script {path}: {exc.strerror or exc}") from None
    answers = data.get("answers") if isinstance(data, dict) else None
    if not isinstance(answers, list):
        raise LLMScriptError(f"LLM script {path} needs a list 'answers:'")
    return ["" if a is None else str(a) for a in answers]


class LLMClient:
    """Completes chat messages through litellm, with cache, replay, script and retries."""

    def __init__(self, settings: LLMSettings, answers: Sequence[str] | None = None) -> None:
        self.settings = settings
        self._answers: list[str] | None = None
        self._next_answer = 0
        self._bundle: Any = None
        if settings.mode == "bundle":
            from twostep.replay import BundleError, load_bundle

            assert settings.bundle is not None
            try:
                self._bundle = load_bundle(settings.bundle)
            except BundleError as error:
                raise LLMBundleMiss(str(error)) from None
        if settings.mode == "scripted":
            if answers is None:
                if settings.script is None:
                    raise LLMScriptError(
                        "LLMSettings.mode=scripted needs LLMSettings.script=<file.yaml>"
                    )
                answers = load_script(settings.script)
            self._answers = list(answers)

    # ------------------------------------------------------------------ keys

    def request(self, messages: Sequence[Message], seed: int) -> dict[str, Any]:
        """The request as it is cached: everything that decides the answer, no secret."""
        s = self.settings
        return {
            "format": CACHE_FORMAT,
            "model": s.model,
            "messages": [{"role": m["role"], "content": m["content"]} for m in messages],
            "temperature": s.temperature,
            "top_p": s.top_p,
            "max_tokens": s.max_tokens,
            "seed": seed,
            "api_base": "local" if s.local else (s.api_base and redact_text(s.api_base)),
            "extra": {k: v for k, v in sorted(s.extra.items()) if not _SECRET_PARAM.search(k)},
        }

    @staticmethod
    def cache_key(request: Mapping[str, Any]) -> str:
        blob = json.dumps(request, sort_keys=True, ensure_ascii=False, default=str)
        return hashlib.sha256(blob.encode()).hexdigest()

    def cache_path(self, key: str) -> Path:
        return self.settings.cache_dir / key[:2] / f"{key}.json"

    # ------------------------------------------------------------------ calls

    def complete(
        self, messages: Sequence[Message], seed: int, about: Mapping[str, Any] | None = None
    ) -> LLMResponse:
        """Answer ``messages``; ``seed`` goes to the provider and into the cache key.

        ``about`` says what the call is for (``step``, ``domain``, ``task``, ``agents``,
        ``helper``): a replay bundle finds its answer by it (``mode="bundle"``)."""
        start = time.perf_counter()
        s = self.settings
        if s.mode == "scripted":
            return self._scripted(start)
        request = self.request(messages, seed)
        if s.mode == "bundle":
            return self._replayed(request, seed, about or {}, start)
        key = self.cache_key(request)
        if s.use_cache or s.mode == "replay":
            hit = self._read_cache(key, replay=s.mode == "replay")
            if hit is not None:
                seconds = time.perf_counter() - start
                recorded = float(hit.get("seconds", 0.0))
                return LLMResponse(hit["text"], True, False, s.model, seconds, recorded, key)
        if s.mode == "replay":
            last = str(request["messages"][-1]["content"]) if request["messages"] else ""
            snippet = " ".join(last.split())[-80:]
            raise LLMCacheMiss(
                f"LLMSettings.mode=replay: no cached answer in {s.cache_dir} for model {s.model}, "
                f"seed {seed} (request {key[:12]}, prompt ending '...{snippet}'); "
                "record it once with LLMSettings.mode=live"
            )
        kwargs, secret = self._call_arguments(request)  # missing credentials: at once
        # Importing litellm (seconds, once per process) is not the call's time: it would be
        # charged to the first call of every job as LLM and so planning time.
        imported = time.perf_counter()
        _import_litellm(s.model)
        start += time.perf_counter() - imported
        text = self._call_live(kwargs, secret)
        seconds = time.perf_counter() - start
        if s.use_cache:
            self._write_cache(key, request, text, seconds)
        return LLMResponse(text, False, False, s.model, seconds, seconds, key)

    def _scripted(self, start: float) -> LLMResponse:
        assert self._answers is not None
        if self._next_answer >= len(self._answers):
            raise LLMScriptError(
                f"scripted LLM answers used up: the script "
                f"{self.settings.script or '(in memory)'} has {len(self._answers)} answer(s), "
                f"call {self._next_answer + 1} needs another"
            )
        text = self._answers[self._next_answer]
        self._next_answer += 1
        return LLMResponse(text, False, True, "scripted", time.perf_counter() - start)

    def _replayed(
        self, request: dict[str, Any], seed: int, about: Mapping[str, Any], start: float
    ) -> LLMResponse:
        """The bundle's answer for the call ``about`` describes (see the class docstring)."""
        from twostep.replay import BundleMiss

        s = self.settings
        bundle = self._bundle
        step = str(about.get("step", ""))
        try:
            domain, task = str(about["domain"]), int(about["task"])
            agents, helper = int(about["agents"]), int(about["helper"])
        except (KeyError, TypeError, ValueError):
            raise LLMBundleMiss(
                "LLMSettings.mode=bundle: the call does not say which task, N and helper it is for"
            ) from None
        try:
            entry = bundle.entry(domain, task, agents, s.model, seed)
        except BundleMiss as error:
            raise LLMBundleMiss(str(error)) from None
        run = bundle.run(entry.run)
        if step == "translate":
            recorded = entry.translations[helper - 1] if helper <= len(entry.translations) else None
            if recorded is None:
                raise LLMBundleMiss(
                    f"{run.file} logs no translations of its model (LLMSettings.translator=llm "
                    "replays them): use LLMSettings.translator=rules"
                )
            text, line = recorded, entry.line
        else:
            if not 1 <= helper <= len(entry.answers):
                raise LLMBundleMiss(
                    f"{run.where(entry.line)} holds {len(entry.answers)} answer(s); helper "
                    f"{helper} has none"
                )
            answer = entry.answers[helper - 1]
            text, line = answer.text, answer.line
        source = {
            "kind": "replayed",
            "model": run.model,
            "run": run.id,
            "file": run.file,
            "line": line,
            "bundle": str(bundle.path or s.bundle),
        }
        # The key a live call would have, marked as replayed: never confused with one.
        key = self.cache_key({**request, "replayed_from": f"{run.id}:{run.sha256}"})
        return LLMResponse(
            text, False, False, run.model, time.perf_counter() - start, 0.0, key, source
        )

    def _call_arguments(self, request: Mapping[str, Any]) -> tuple[dict[str, Any], str | None]:
        """litellm's arguments for ``request``, and the key among them (None: no key)."""
        s = self.settings
        kwargs: dict[str, Any] = {
            "model": s.model,
            "messages": request["messages"],
            "temperature": s.temperature,
            "max_tokens": s.max_tokens,
            "seed": request["seed"],
            "timeout": s.timeout_s,
            "max_retries": 0,  # retries are ours
            "drop_params": True,  # e.g. Anthropic has no `seed`: it stays in our cache key
            **s.extra,
        }
        if s.top_p is not None:
            kwargs["top_p"] = s.top_p
        if s.api_base:
            kwargs["api_base"] = s.api_base
        secret: str | None = None
        env = s.key_env
        if env:
            secret = os.environ.get(env) or None
            if secret is None:
                raise LLMCredentialsError(credentials_message(s))
            kwargs["api_key"] = secret
        elif (s.api_base or s.local) and s.provider == "openai":
            kwargs["api_key"] = "not-needed"  # OpenAI-compatible servers ignore it
        return kwargs, secret

    def _call_live(self, kwargs: Mapping[str, Any], secret: str | None) -> str:
        """litellm's answer, with the one retry loop (the module docstring)."""
        s = self.settings
        litellm = _import_litellm()
        attempt = 0
        while True:
            try:
                response = litellm.completion(**kwargs)
                content = response.choices[0].message.content
                return content if isinstance(content, str) else ""
            except (litellm.AuthenticationError, litellm.PermissionDeniedError) as exc:
                status = getattr(exc, "status_code", None)
                raise LLMCredentialsError(rejected_message(s, status)) from None
            except Exception as exc:
                if not _retryable(litellm, exc) or attempt >= s.max_retries:
                    what = _scrub(f"{type(exc).__name__}: {exc}", secret)
                    tries = f" after {attempt + 1} attempts" if attempt else ""
                    raise LLMCallError(f"LLM call to {s.model} failed{tries}: {what}") from None
                time.sleep(min(s.backoff_s * 2**attempt, 60.0))
                attempt += 1

    # ------------------------------------------------------------------ cache

    def _read_cache(self, key: str, replay: bool) -> dict[str, Any] | None:
        """The cached entry, or None when there is none; a corrupt one is reported."""
        path = self.cache_path(key)
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return None
        except (OSError, ValueError) as error:
            problem = f"{type(error).__name__}: {error}"
        else:
            if isinstance(data, dict) and isinstance(data.get("text"), str):
                return data
            problem = "no answer text in it"
        if replay:
            raise LLMCacheCorrupt(
                f"LLMSettings.mode=replay: the cache entry {path} is corrupt ({problem}); "
                "delete it and record it again with LLMSettings.mode=live"
            )
        log.warning("LLM cache entry %s is corrupt (%s): asking the model again", path, problem)
        return None

    def _write_cache(self, key: str, request: Mapping[str, Any], text: str, seconds: float) -> None:
        entry = {
            "key": key,
            "request": request,
            "text": text,
            "seconds": seconds,
            "model": self.settings.model,
            "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        }
        # atomic: parallel jobs (and a kill -9) never leave half an entry
        write_json_atomic(self.cache_path(key), entry, indent=1)


def _retryable(litellm: Any, exc: Exception) -> bool:
    if isinstance(exc, litellm.BadRequestError | litellm.NotFoundError):
        return False
    transient = (
        litellm.RateLimitError,
        litellm.Timeout,
        litellm.APIConnectionError,
        litellm.InternalServerError,
        litellm.ServiceUnavailableError,
        litellm.BadGatewayError,
    )
    if isinstance(exc, transient):
        return True
    status = getattr(exc, "status_code", None)
    return isinstance(status, int) and status >= 500


def _scrub(text: str, secret: str | None) -> str:
    return redact_text(" ".join(text.split()), [secret])[:400]
