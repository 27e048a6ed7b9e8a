"""twostep/redaction.py: credentials inside URLs, keys given as variable names, known
secrets, on hand-written inputs."""

from __future__ import annotations

import pytest

from twostep.redaction import looks_like_a_key, redact_config, redact_text


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
