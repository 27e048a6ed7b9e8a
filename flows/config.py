"""The structured config schema: every key the Hydra app accepts, with its type.

Registered with Hydra's ConfigStore as ``twostep_schema`` and used as the first entry
of ``conf/config.yaml``'s defaults list, so a typo in an override (``tsak=3``) or a value
of the wrong type fails at once with Hydra's message naming the key.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from hydra.core.config_store import ConfigStore


@dataclass
class DomainConfig:
    name: str = "blocksworld"
    agent_predicates: list[str] = field(default_factory=list)


@dataclass
class MethodConfig:
    name: str = "twostep"  # sa | ma | twostep


@dataclass
class DecomposerConfig:
    name: str = "goal-split"  # goal-split | expert | llm
    link_degree: int = 2


@dataclass
class LLMConfig:
    model: str = "openai/gpt-4o"
    temperature: float = 0.0
    top_p: float = 1.0
    max_tokens: int = 512
    api_base: str | None = None
    api_key_env: str | None = None
    mode: str = "live"  # live | replay | scripted
    cache_dir: str = "outputs/llm-cache"
    script: str | None = None
    max_retries: int = 4
    backoff_s: float = 1.0
    timeout_s: float = 60.0
    local_model: str | None = None  # llm=local: path of a GGUF file (default: SmolLM2)


@dataclass
class PlannerConfig:
    alias: str = "lama-first"  # lama (anytime, paper) | lama-first
    time_limit_s: float = 60.0  # CPU search limit for SA/MA; divided by N per agent in TwoStep
    memory_limit_mb: int | None = None


@dataclass
class DataConfig:
    root: str = "data"


@dataclass
class OutputConfig:
    root: str = "outputs"


@dataclass
class TwostepConfig:
    domain: DomainConfig = field(default_factory=DomainConfig)
    method: MethodConfig = field(default_factory=MethodConfig)
    decomposer: DecomposerConfig = field(default_factory=DecomposerConfig)
    llm: LLMConfig = field(default_factory=LLMConfig)
    planner: PlannerConfig = field(default_factory=PlannerConfig)
    data: DataConfig = field(default_factory=DataConfig)
    output: OutputConfig = field(default_factory=OutputConfig)
    experiment: Any = None
    task: int = 5
    agents: int = 2
    seed: int = 0
    score_mode: str = "exact"
    compare_sa: bool = True


def register() -> None:
    ConfigStore.instance().store(name="twostep_schema", node=TwostepConfig)
