"""LLM access for TwoStep: one cached, replayable client over litellm, the prompts, parsing.

Modules: :mod:`~twostep.llm.client` (``LLMSettings``, ``LLMClient``),
:mod:`~twostep.llm.prompts` (the generator and translator prompts),
:mod:`~twostep.llm.parsing` (English condition and PDDL goal from the answers),
:mod:`~twostep.llm.local` (optional in-process llama.cpp server; imported only when used).
Importing this package does not import litellm.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace

from twostep.llm.client import (
    LLMBundleMiss,
    LLMCacheCorrupt,
    LLMCacheMiss,
    LLMCallError,
    LLMClient,
    LLMCredentialsError,
    LLMError,
    LLMResponse,
    LLMScriptError,
    LLMSettings,
)


@contextmanager
def open_client(settings: LLMSettings) -> Iterator[LLMClient]:
    """A client for ``settings``; with ``local=True`` in live mode, also the local server."""
    if settings.local and settings.mode == "live" and not settings.api_base:
        from twostep.llm.local import local_server

        alias = settings.model.split("/", 1)[-1]
        with local_server(alias=alias) as api_base:
            yield LLMClient(replace(settings, api_base=api_base))
    else:
        yield LLMClient(settings)


__all__ = [
    "LLMBundleMiss",
    "LLMCacheCorrupt",
    "LLMCacheMiss",
    "LLMCallError",
    "LLMClient",
    "LLMCredentialsError",
    "LLMError",
    "LLMResponse",
    "LLMScriptError",
    "LLMSettings",
    "open_client",
]
