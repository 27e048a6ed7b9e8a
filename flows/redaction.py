"""A config with its secrets masked, before it is stored or logged: the config's own rule
that a ``*_env`` key (``llm.api_key_env``) names an environment variable, so a value there
that looks like a key was pasted by mistake. The text masking itself (URL credentials,
provider keys, bearer tokens) is the library's: :mod:`twostep.util.redaction`."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from twostep.util.redaction import MASK, looks_like_a_key, redact_text


def redact_config(data: Any, key: str = "") -> Any:
    """A copy of a (nested) config with every string redacted (:func:`redact_text`) and a
    ``*_env`` value that looks like a key replaced by ``***``."""
    if isinstance(data, Mapping):
        return {k: redact_config(v, str(k)) for k, v in data.items()}
    if isinstance(data, list | tuple):
        return [redact_config(v, key) for v in data]
    if isinstance(data, str):
        if key.endswith("_env") and looks_like_a_key(data):  # names a variable: no key here
            return MASK
        return redact_text(data)
    return data
