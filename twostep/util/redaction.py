"""Secrets kept out of everything that is stored or printed: the one owner of these rules.

* Credentials inside a URL (``https://user:pass@host/v1``) become ``https://***@host/v1``
  (:func:`redact_text`), in any text: a config value, an error line, a file's content;
  so does the value of a query parameter named like a credential
  (``?api_key=...``, ``&token=...``, ``&sig=...``: ``?api_key=***``).
* A setting that names an environment variable (``LLMSettings.api_key_env``) must hold a variable
  *name*; a value that is not one, or that looks like a random token, is taken for a
  pasted key (:func:`looks_like_a_key`): refused before any work, and written as ``***``
  wherever a config is stored (``flows.redaction.redact_config``, the config's side).
* A secret the caller knows (the API key of a call) is replaced wherever it appears, and
  so is anything shaped like a provider key (``sk-...``, Google's ``AIza...``) or a
  bearer token (``Bearer ...``).
* A name (``LLMSettings.model``) that holds a key-shaped part (:func:`holds_a_key`) is refused
  before any work, with a message that does not repeat it.

Plain functions on text and plain data; nothing here reads the environment.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import Any

MASK = "***"

# scheme://userinfo@ : the userinfo part (user, user:password, or a token) is the secret
# (also as Hydra shows an override, its colons escaped: http\://user\:pass@host).
_URL_CREDENTIALS = re.compile(r"\b([A-Za-z][A-Za-z0-9+.\-]*\\?://)[^/@\s'\"<>]+@")
# Provider keys that announce themselves (OpenAI, Anthropic, many gateways: sk-..., sk-ant-...).
_PROVIDER_KEY = re.compile(r"\b(sk-[A-Za-z0-9_\-]{4}|AIza)[A-Za-z0-9_\-*]+")
_BEARER = re.compile(r"\b(Bearer\s+)[A-Za-z0-9._~+/=\-]+", re.IGNORECASE)
# A URL query parameter whose name says it holds a credential: its value is masked.
_QUERY_SECRET = re.compile(
    r"([?&;][A-Za-z0-9_.\-]*(?:key|token|secret|password|passwd|pwd|sig|signature|"
    r"auth|credential|session)[A-Za-z0-9_.\-]*=)[^&#\s'\"<>]+",
    re.IGNORECASE,
)
# A random-looking token: 24 or more letters and digits in one run, mixing both.
_TOKEN_RUN = re.compile(r"[A-Za-z0-9]{24,}")
_VARIABLE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def is_variable_name(text: str) -> bool:
    """Whether ``text`` can name an environment variable (letters, digits, ``_``)."""
    return _VARIABLE_NAME.fullmatch(text) is not None


def looks_like_a_key(value: str) -> bool:
    """Whether a value given as a variable's name is rather a key: not a variable name at
    all (``sk-...``), or a long token that mixes lower- and upper-case letters and digits
    the way generated keys do and variable names do not."""
    if not is_variable_name(value):
        return True
    mixed = (
        any(c.islower() for c in value)
        and any(c.isupper() for c in value)
        and any(c.isdigit() for c in value)
    )
    return len(value) >= 20 and mixed


def redact_text(text: str, secrets: Iterable[str | None] = ()) -> str:
    """``text`` with URL credentials, provider keys and the given ``secrets`` masked."""
    for secret in secrets:
        if secret:
            text = text.replace(secret, MASK)
    text = _URL_CREDENTIALS.sub(rf"\1{MASK}@", text)
    text = _QUERY_SECRET.sub(rf"\1{MASK}", text)
    text = _BEARER.sub(rf"\1{MASK}", text)
    return _PROVIDER_KEY.sub(rf"\1{MASK}", text)


def holds_a_key(text: str) -> bool:
    """Whether a name (a model's, ``openai/gpt-4o``) holds something shaped like a key: a
    provider key (``sk-...``, ``AIza...``), credentials the masking above would hide, or a
    run of 24+ letters and digits that mixes both (model names are words, versions and
    dates: ``Meta-Llama-3.1-70B-Instruct``, ``claude-3-5-sonnet-20241022``)."""
    if redact_text(text) != text:
        return True
    return any(
        any(c.isalpha() for c in run) and any(c.isdigit() for c in run)
        for run in _TOKEN_RUN.findall(text)
    )


def __getattr__(name: str) -> Any:
    """``redact_config`` moved to :mod:`flows.redaction` (the config's rule): the old name
    still imports, with a DeprecationWarning, for one release."""
    if name == "redact_config":
        from twostep import moved_name

        return moved_name(__name__, name, "flows.redaction")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
