"""twostep/util/redaction.py: credentials inside URLs, keys given as variable names, known
secrets, on hand-written inputs."""

from __future__ import annotations

import pytest

from flows.redaction import redact_config
from twostep.util.redaction import looks_like_a_key, redact_text


@pytest.mark.parametrize(
    ("text", "masked"),
    [
        ("https://user:pass@host.org/v1", "https://***@host.org/v1"),
        ("http://token@127.0.0.1:8000", "http://***@127.0.0.1:8000"),
        (r"llm.api_base=http\://u\:p@h\:9/v1", r"llm.api_base=http\://***@h\:9/v1"),  # Hydra's
        ("postgresql://me:pw@db:5432/mlflow", "postgresql://***@db:5432/mlflow"),
        ("sqlite:////tmp/a@b/mlflow.db", "sqlite:////tmp/a@b/mlflow.db"),  # a path, no user
        ("mail me@example.org", "mail me@example.org"),  # not a URL
        ("key sk-proj-abcdefgh123", "key sk-proj***"),
    ],
)
def test_redact_text(text: str, masked: str) -> None:
    assert redact_text(text) == masked


def test_known_secrets_are_replaced_wherever_they_appear() -> None:
    assert redact_text("Bearer s3cr3t-value rejected", ["s3cr3t-value", None]) == (
        "Bearer *** rejected"
    )


@pytest.mark.parametrize(
    ("value", "is_key"),
    [
        ("OPENAI_API_KEY", False),
        ("my_gateway_key", False),
        ("TWOSTEP_TEST_CANARY_KEY", False),
        ("sk-ant-api03-xyz", True),  # not a variable name at all
        ("aB3dEfGh1234567890XyZw", True),  # long, mixed case and digits: generated
        ("OPENAI_API_KEY_2", False),
    ],
)
def test_looks_like_a_key(value: str, is_key: bool) -> None:
    assert looks_like_a_key(value) is is_key


def test_redact_config_masks_urls_and_keys_given_as_names() -> None:
    config = {
        "llm": {"api_base": "https://u:p@x/v1", "api_key_env": "sk-live-123", "model": "m"},
        "mlflow": {"tracking_uri": "http://admin:pw@mlflow:5000"},
        "hosts": ["https://a:b@c", 3],
        "other_env": "HOME",
    }
    assert redact_config(config) == {
        "llm": {"api_base": "https://***@x/v1", "api_key_env": "***", "model": "m"},
        "mlflow": {"tracking_uri": "http://***@mlflow:5000"},
        "hosts": ["https://***@c", 3],
        "other_env": "HOME",
    }


# issue 39, finding 7: keys in query strings, bearer tokens, keys inside names
@pytest.mark.parametrize(
    ("text", "masked"),
    [
        ("http://h:9/v1?api_key=AIzaXyz0123", "http://h:9/v1?api_key=***"),
        ("https://h/v1?v=2&access_token=abc.def&x=1", "https://h/v1?v=2&access_token=***&x=1"),
        ("https://h/?sig=a%2Fb#frag", "https://h/?sig=***#frag"),
        ("'https://h/v1?key=abc'", "'https://h/v1?key=***'"),  # as a yaml file quotes it
        ("https://h/?api-version=2024-02-01", "https://h/?api-version=2024-02-01"),  # no key
        ("Authorization: Bearer abc.DEF-123", "Authorization: Bearer ***"),
        ("a Google key AIzaSyA0123456789", "a Google key AIza***"),
    ],
)
def test_query_string_keys_and_tokens_are_masked(text: str, masked: str) -> None:
    assert redact_text(text) == masked


@pytest.mark.parametrize(
    ("model", "holds"),
    [
        ("openai/gpt-4o", False),
        ("anthropic/claude-3-5-sonnet-20241022", False),
        ("together_ai/meta-llama/Meta-Llama-3.1-70B-Instruct-Turbo", False),
        ("ollama/llama3.1:8b", False),
        ("hosted_vllm/Qwen/Qwen2.5-7B-Instruct", False),
        ("ft:gpt-4o-mini-2024-07-18:my-org::9abcDEF1", False),
        ("openai/sk-proj-0123456789", True),
        ("gemini/AIzaSyA0123456789", True),
        ("openai/gskQ7w2Lr9Xb4Tn8Vc1Mz5Kp3Hd6", True),  # 24+ letters and digits in one run
    ],
)
def test_a_key_inside_a_model_name_is_recognised(model: str, holds: bool) -> None:
    from twostep.util.redaction import holds_a_key

    assert holds_a_key(model) is holds
