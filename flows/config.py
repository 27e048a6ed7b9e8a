"""The structured config schema: every key the Hydra app accepts, with its type.

Registered with Hydra's ConfigStore as ``twostep_schema`` and used as the first entry
of ``conf/config.yaml``'s defaults list, so a value of the wrong type (``agents=two``,
``orchestration.task_runner=spark``) fails at once with Hydra's message naming the key. A
typo in a key (``tsak=3``, ``+agnets=3``, ``orchestration.task_runer=dask``) or an option
(``domain=nosuch``) is refused before Hydra runs, in one line naming the closest key or
the choices (:func:`override_problem`): Hydra would suggest ``+tsak=3``, which then runs
with the key ignored.

Values live in ``conf/``; the defaults here only give each key its type. Where a key
is a library setting, its default is the library dataclass's default (one default per
setting); the one place that turns a config into library objects is :mod:`flows.build`.
"""

from __future__ import annotations

import contextlib
import difflib
import enum
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field, fields, is_dataclass
from importlib import resources
from pathlib import Path
from typing import Any, cast, get_type_hints

from hydra.core.config_store import ConfigStore
from omegaconf import OmegaConf

from twostep.embodied import ExecutorSettings
from twostep.llm.client import LLMSettings
from twostep.makespan import DEFAULT_SEARCH_BUDGET
from twostep.planner import PlannerSettings
from twostep.tasks.benchmark import DEFAULT_DATA_ROOT

_LLM = LLMSettings()
_PLANNER = PlannerSettings()
_EXECUTOR = ExecutorSettings()


@dataclass
class DomainConfig:
    name: str = "blocksworld"
    agent_predicates: list[str] = field(default_factory=list)


# OmegaConf deprecates a structured config that subclasses Dict (MethodConfig, below) but
# supports it: it is how a group keeps its common keys typed and takes each option's own.
warnings.filterwarnings("ignore", message="Class `MethodConfig` subclasses `Dict`")


@dataclass
class MethodConfig(dict[str, Any]):
    """The method (``conf/method/<name>.yaml``, a name of
    :data:`twostep.methods.registry.METHODS`) and its options: the keys of the method's
    file besides these, checked against the method's run function by the registry."""

    name: str = "twostep"  # sa | ma | twostep | plan-deal | portfolio | portfolio-lite
    # A joint schedule longer than the SA plan gives way to it (run_twostep's own
    # parameter of the same name; plan-deal's and the portfolios' too); ignored by sa and ma.
    fallback_if_longer: bool = True


@dataclass
class DecomposerConfig:
    """TwoStep's subgoal source (read by ``method=twostep`` only)."""

    name: str | None = None  # goal-split | expert | llm | plan-split (null: none chosen)
    link_degree: int = 2
    # The old spelling's (method=twostep decomposer=plan-deal decomposer.cut=free), for one
    # more release: plan-deal's and the portfolios' options, now theirs under method.*.
    cut: str = "best"  # free | holding | mover | best (now method.cut)
    rebind: bool = True  # now method.rebind
    owner_search: bool = True  # now method.owner_search


class ExecutorName(enum.StrEnum):
    symbolic = "symbolic"  # the joint schedule is the result
    embodied = "embodied"  # plans then run on the task's floor plan (twostep.embodied)


@dataclass
class ExecutorConfig:
    """How plans are executed after planning: ``symbolic`` (the joint schedule) or
    ``embodied`` (:class:`twostep.embodied.ExecutorSettings`, same names and defaults;
    the seed is the job's)."""

    name: ExecutorName = ExecutorName.symbolic
    max_steps: int | None = _EXECUTOR.max_steps
    stall_limit: int = _EXECUTOR.stall_limit
    backoff_radius: int = _EXECUTOR.backoff_radius
    random_start: bool = _EXECUTOR.random_start
    # The scene a real AlfWorld problem is placed on (FloorPlanN, or open); None: found
    # from the problem (twostep.embodied.floor_plan_for_task)
    layout: str | None = None
    # GIF + timeline in the job directory (MLflow artifacts); None: every single run, and
    # in a sweep the jobs of seed 0 (twostep.embodied.draws_pictures)
    render: bool | None = None


@dataclass
class LLMConfig:
    """:class:`twostep.llm.LLMSettings` (same names, same defaults; built by flows.build)."""

    model: str = _LLM.model
    temperature: float = _LLM.temperature
    top_p: float | None = _LLM.top_p  # null: not sent (models that refuse temperature and top_p)
    max_tokens: int = _LLM.max_tokens
    api_base: str | None = _LLM.api_base
    api_key_env: str | None = _LLM.api_key_env  # the variable's NAME; never the key itself
    mode: str = _LLM.mode  # live | replay | scripted | bundle
    cache_dir: str = str(_LLM.cache_dir)
    script: str | None = None
    max_retries: int = _LLM.max_retries
    backoff_s: float = _LLM.backoff_s
    timeout_s: float = _LLM.timeout_s
    use_cache: bool = _LLM.use_cache
    local: bool = _LLM.local  # llm=local: serve the model from an in-process llama.cpp server
    bundle: str | None = (
        None  # llm=replay: the replay bundle's folder (twostep-data import-answers)
    )
    translator: str = _LLM.translator  # llm | rules: who turns English subgoals into PDDL


@dataclass
class PlannerConfig:
    """:class:`twostep.planner.PlannerSettings`; ``time_limit_s`` is its
    ``search_time_limit_s`` (CPU search limit for SA/MA; divided by N per agent in TwoStep)."""

    alias: str = _PLANNER.alias  # lama (anytime, paper) | lama-first
    time_limit_s: float = _PLANNER.search_time_limit_s
    # each Fast Downward process (grounding, the planner's translator and search); null: 4096
    memory_limit_mb: int | None = _PLANNER.memory_limit_mb
    # CPU seconds to ground the task (Fast Downward's translator); null: time_limit_s
    grounding_time_limit_s: float | None = None


@dataclass
class DataConfig:
    # The benchmark data installed with the package, wherever the command runs; any
    # folder in the LLM+P layout instead (data.root=/path/to/llmp-benchmark).
    root: str = str(DEFAULT_DATA_ROOT)


@dataclass
class OutputConfig:
    root: str = "outputs"


@dataclass
class MLflowConfig:
    """Where a job's params, metrics and artifacts go (the contract: docs/tracking.md)."""

    enabled: bool = True
    tracking_uri: str = "sqlite:///outputs/mlflow.db"
    artifact_location: str | None = None  # for experiments created here; null: the store's
    experiment: str | None = None  # null: derived from the sweep's overrides ("twostep" for runs)
    connect_timeout_s: float = 10.0  # a remote store that does not answer in time is an error


class TaskRunner(enum.StrEnum):
    default = "default"  # Prefect's thread pool in the job's own process
    dask = "dask"  # a Dask cluster: orchestration.dask_address, or one LocalCluster per sweep


@dataclass
class OrchestrationConfig:
    """How jobs run: Prefect on or off, which server, task runner, caches, progress."""

    # null (auto): sweeps run jobs as Prefect flows; a single run does only when a server
    # is already up (twostep-services up, prefect_api_url). true: always (a single run
    # starts a temporary server if none is up). false: never (the library directly).
    prefect: bool | None = None
    prefect_api_url: str | None = None  # an existing server; null: one per sweep (or run)
    prefect_home: str = "outputs/prefect"  # the started server's database and settings
    result_storage: str = "outputs/prefect/results"  # persisted task results (the task cache)
    server_host: str = "127.0.0.1"
    server_startup_timeout_s: float = 180.0  # a fresh database migrates first: be generous
    prefect_log_level: str = "WARNING"
    task_runner: TaskRunner = TaskRunner.default
    dask_address: str | None = None  # tcp://host:8786 of an existing cluster
    dask_workers: int = 2  # LocalCluster size when task_runner=dask and no address
    job_store: str = "outputs/jobs"  # finished jobs by job key: never recomputed
    reuse_results: bool = True
    progress: bool = True  # one line per finished job of a sweep


@dataclass
class TwostepConfig:
    domain: DomainConfig = field(default_factory=DomainConfig)
    method: MethodConfig = field(default_factory=MethodConfig)
    decomposer: DecomposerConfig = field(default_factory=DecomposerConfig)
    llm: LLMConfig = field(default_factory=LLMConfig)
    planner: PlannerConfig = field(default_factory=PlannerConfig)
    executor: ExecutorConfig = field(default_factory=ExecutorConfig)
    data: DataConfig = field(default_factory=DataConfig)
    output: OutputConfig = field(default_factory=OutputConfig)
    mlflow: MLflowConfig = field(default_factory=MLflowConfig)
    orchestration: OrchestrationConfig = field(default_factory=OrchestrationConfig)
    experiment: Any = None
    task: int = 5
    agents: int = 2
    seed: int = 0
    score_mode: str = "exact"
    # twostep.makespan.SearchBudget: the exact scorer's node and time budget (null: none)
    score_max_nodes: int | None = DEFAULT_SEARCH_BUDGET.max_nodes
    score_time_limit_s: float | None = DEFAULT_SEARCH_BUDGET.time_limit_s
    compare_sa: bool = True


def agents_run(method: str, agents: int | None) -> int | None:
    """The number of agents a job runs: SA plans for one agent whatever ``agents`` says."""
    return 1 if method == "sa" else agents


def register() -> None:
    """The schema in Hydra's ConfigStore, and the ``twostep_agents`` resolver the run and
    sweep directory names use (``_sa_n1``, not the ``agents`` SA ignores)."""
    ConfigStore.instance().store(name="twostep_schema", node=TwostepConfig)
    OmegaConf.register_new_resolver("twostep_agents", agents_run, replace=True)


def typed(cfg: object) -> TwostepConfig:
    """A job's config, composed over this schema (Hydra's DictConfig, validated by
    OmegaConf on every assignment), seen as what it is: a :class:`TwostepConfig`."""
    return cast(TwostepConfig, cfg)


# ----------------------------------------------------------------- command-line keys
# Hydra refuses an unknown key with several lines ending in a hint to add it with `+`,
# and then takes `+agnets=3` silently: a typo would run another experiment. The command
# checks its overrides against the schema first (:func:`override_problem`).

HYDRA_GROUP_PREFIX = "hydra"


def schema_keys(node: type = TwostepConfig, prefix: str = "") -> dict[str, bool]:
    """Every dotted key of the schema -> whether it holds any value (``Any``: keys below
    it are its own, e.g. ``experiment``; a group that is a dict as well: its options,
    ``method``)."""
    keys: dict[str, bool] = {}
    hints = get_type_hints(node)
    for item in fields(node):  # type: ignore[arg-type]
        name = f"{prefix}{item.name}"
        kind = hints[item.name]
        keys[name] = kind is Any or (isinstance(kind, type) and issubclass(kind, dict))
        if is_dataclass(kind):
            keys.update(schema_keys(kind, f"{name}."))  # type: ignore[arg-type]
    return keys


def group_options(group: str, config_dirs: Sequence[str] = (), complete: bool = False) -> list[str]:
    """The options of a config group: its YAML files in the installed configs and in the
    folders given with ``--config-dir``; ``complete``: with Hydra's own list for Hydra's
    groups (its plugins' options too: slower)."""
    options: set[str] = set()
    folders = [resources.files("flows.conf") / group, *(Path(d) / group for d in config_dirs)]
    for folder in folders:
        with contextlib.suppress(OSError):
            options |= {
                item.name.removesuffix(".yaml")
                for item in folder.iterdir()
                if item.name.endswith(".yaml")
            }
    if complete and group.startswith(HYDRA_GROUP_PREFIX + "/"):
        from hydra import initialize_config_module
        from hydra.core.global_hydra import GlobalHydra

        with initialize_config_module(config_module="flows.conf", version_base="1.3"):
            options |= set(GlobalHydra.instance().config_loader().get_group_options(group))
    return sorted(options)


def config_groups(config_dirs: Sequence[str] = ()) -> list[str]:
    """The app's config groups (top-level folders of its configs, Hydra's own apart)."""
    groups: set[str] = set()
    for folder in [resources.files("flows.conf"), *(Path(d) for d in config_dirs)]:
        with contextlib.suppress(OSError):
            groups |= {
                item.name
                for item in folder.iterdir()
                if item.is_dir() and not item.name.startswith(("_", HYDRA_GROUP_PREFIX))
            }
    return sorted(groups)


def did_you_mean(key: str, known: Sequence[str]) -> str:
    """``unknown key 'agnets': did you mean 'agents'?`` (without a close one: the
    top-level keys)."""
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.6)
    if not close and "." in key:  # a typo in the last part: its siblings
        parent, _, last = key.rpartition(".")
        siblings = [k.rpartition(".")[2] for k in known if k.rpartition(".")[0] == parent]
        near = difflib.get_close_matches(last, siblings, n=1, cutoff=0.6)
        close = [f"{parent}.{near[0]}"] if near else []
    if close:
        return f"unknown key '{key}': did you mean '{close[0]}'?"
    top = sorted({k.split(".")[0] for k in known})
    return f"unknown key '{key}' (keys: {', '.join(top)})"


def _option_values(override: Any) -> list[str]:
    """The options an override of a group names (a sweep's each; none for functions
    such as ``glob(*)``, which Hydra expands)."""
    if override.is_sweep_override():
        try:
            return [str(v) for v in override.sweep_iterator()]
        except Exception:
            return []
    value = override.value()
    return [] if value is None or not isinstance(value, str | int) else [str(value)]


def override_problem(arguments: Sequence[str]) -> str | None:
    """The first override of a command line (``twostep``'s arguments) that names a key or
    a group option the app does not have, as one line (None: every one is known, or Hydra
    reports the line itself). ``+key=...`` of an unknown key is refused as well: the
    schema has every key a job reads."""
    from hydra._internal.utils import get_args_parser
    from hydra.core.override_parser.overrides_parser import OverridesParser

    try:
        parsed = get_args_parser().parse_args(list(arguments))
        overrides = OverridesParser.create().parse_overrides(parsed.overrides)
    except (Exception, SystemExit):  # Hydra says what is wrong with the line itself
        return None
    config_dirs = [parsed.config_dir] if parsed.config_dir else []
    keys = schema_keys()
    groups = config_groups(config_dirs)
    for override in overrides:
        key = override.key_or_group
        if override.is_hydra_override() and "/" not in key:
            continue  # Hydra's own settings: Hydra checks them
        if "/" in key or (key in groups and override.package is None and not override.is_delete()):
            if "/" in key and not key.startswith(HYDRA_GROUP_PREFIX + "/"):
                continue  # a nested group (domain/x=...): Hydra's to resolve
            values = [v for v in _option_values(override) if v != "null"]
            options = group_options(key, config_dirs)
            if not set(values) <= set(options):
                options = group_options(key, config_dirs, complete=True)
            for value in values:
                if value not in options:
                    return f"unknown {key} '{value}' (choices: {', '.join(options)})"
            continue
        if key.startswith(f"{METHOD_GROUP}.") and key not in keys and not override.is_add():
            known = method_option_keys(_methods_chosen(overrides), config_dirs)
            if key not in known:
                return did_you_mean(key, sorted({*known, f"{METHOD_GROUP}.name"}))
            continue
        if key in keys or any(key.startswith(f"{k}.") for k, open_ in keys.items() if open_):
            if override.is_add() and not override.is_force_add() and key in keys:
                return f"{key} is a key already: set it without '+' ({key}=...)"
            continue
        return did_you_mean(key, [*keys, *groups])
    return None


METHOD_GROUP = "method"  # its options are the keys of the chosen method's file


def _chosen(overrides: Sequence[Any], group: str, default: str | None) -> list[str | None]:
    """The options a command line chooses for ``group`` (none: its default)."""
    chosen = [v for o in overrides if o.key_or_group == group for v in _option_values(o)]
    return list(chosen) or [default]


def _methods_chosen(overrides: Sequence[Any]) -> list[str]:
    """The methods a command line runs. With no method given: the schema's ``twostep``,
    read as both methods the command can compose, plan-deal (``conf/config.yaml``'s
    default; ``method=twostep`` without a decomposer, :func:`flows.spelling.new_spelling`)
    and twostep (a decomposer given without a method: ``conf/decomposer/*.yaml``)."""
    from flows.spelling import new_spelling

    methods = _chosen(overrides, METHOD_GROUP, TwostepConfig().method.name)
    decomposers = _chosen(overrides, "decomposer", None)
    return sorted(
        {str(new_spelling(m, d) or m) for m in methods for d in decomposers}
        | set(map(str, methods))
    )


def method_option_keys(methods: Sequence[str], config_dirs: Sequence[str] = ()) -> set[str]:
    """``method.<key>`` of every key the files of ``methods`` (``conf/method/<name>.yaml``,
    and those of ``--config-dir`` folders) set: the options a command line may set."""
    import yaml

    keys: set[str] = set()
    for method in methods:
        for folder in [resources.files("flows.conf"), *(Path(d) for d in config_dirs)]:
            with contextlib.suppress(OSError, yaml.YAMLError):
                data = yaml.safe_load((folder / METHOD_GROUP / f"{method}.yaml").read_text())
                if isinstance(data, dict):
                    keys |= {f"{METHOD_GROUP}.{k}" for k in data}
    return keys
