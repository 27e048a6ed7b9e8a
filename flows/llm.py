"""The LLM decomposer from the config: settings mapping and the client's lifetime.

``llm=local`` starts a llama.cpp server for the duration of the job, so the decomposer
is handed out by a context manager that owns the client.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from twostep.decomposers.llm import LLMDecomposer
from twostep.llm import LLMSettings, open_client


def llm_settings(cfg: Any) -> LLMSettings:
    llm = cfg.llm
    return LLMSettings(
        model=llm.model,
        temperature=float(llm.temperature),
        top_p=None if llm.top_p is None else float(llm.top_p),
        max_tokens=int(llm.max_tokens),
        api_base=llm.api_base,
        api_key_env=llm.api_key_env,
        mode=llm.mode,
        cache_dir=Path(llm.cache_dir),
        script=Path(llm.script) if llm.script else None,
        max_retries=int(llm.max_retries),
        backoff_s=float(llm.backoff_s),
        timeout_s=float(llm.timeout_s),
        use_cache=bool(llm.get("use_cache", True)),
        local=bool(llm.get("local", False)),
    )


@contextmanager
def llm_decomposer(cfg: Any) -> Iterator[LLMDecomposer]:
    """The LLM decomposer for one job; stops a local model server afterwards."""
    with open_client(llm_settings(cfg)) as client:
        yield LLMDecomposer(client)
