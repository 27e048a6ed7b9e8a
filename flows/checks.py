"""Checks before any work: every config value in its allowed range (one table,
:data:`VALUE_RULES`), the task where the config says it is, and every location a job
writes to writable. Each problem is one line naming the key (or the location) and what is
allowed; the command prints it and exits 2.

The Hydra callback (:mod:`flows.sweep_callback`) runs them before Hydra creates the run
directory of a single run (:func:`input_problem`, :func:`check_writable`) or the sweep
directory of a multirun (:func:`sweep_problem`: every value the sweep lists), so a refused
command leaves no folder, file or record behind; :func:`flows.build.check_job` runs
:func:`check_values` again for every job (a job started from Python, or by another
sweeper), before any planning.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flows.locations import local_folder, write_problem
from flows.wording import worded


class JobError(Exception):
    """A config that names something that does not exist or does not fit together (an
    input error: one line, exit 2)."""


class ValidationError(Exception):
    """A config value out of range, or a location that cannot be written (exit 2)."""


# ----------------------------------------------------------------- value rules
# One table: every config value's allowed range (:data:`VALUE_RULES`), checked by
# :func:`value_problems` for one job and for every value a sweep lists. A new range is one
# row here. Each check gets the key's name as shown (``method``, not ``method.name``) and
# its value, and returns the problem as one line (None: allowed).

Check = Callable[[str, Any], "str | None"]


def one_of(allowed: Callable[[], Iterable[str]], optional: bool = False) -> Check:
    """A choice among ``allowed()`` (read when checked: the lists live in the library;
    ``optional``: or null)."""

    def check(key: str, value: Any) -> str | None:
        choices = tuple(allowed())
        if str(value) in choices or (value is None and optional):
            return None
        return f"{key}={value} is not allowed (allowed: {', '.join(choices)})"

    return check


def at_least(low: int, optional: bool = False, hint: str = "") -> Check:
    """An integer >= ``low`` (``optional``: or null)."""

    def check(key: str, value: Any) -> str | None:
        if value is None and optional:
            return None
        try:
            ok = int(value) >= low
        except (TypeError, ValueError):
            ok = False
        if ok:
            return None
        if low > 0:
            return f"{key}={value} must be at least {low}"
        return f"{key}={value} must be >= {low}{hint}"

    return check


def memory_mb(key: str, value: Any) -> str | None:
    """A memory limit in MB: at least the planner's smallest, or null (its default)."""
    from twostep.programs.processes import DEFAULT_MEMORY_LIMIT_MB, MIN_MEMORY_LIMIT_MB

    if value is None:
        return None
    try:
        ok = int(value) >= MIN_MEMORY_LIMIT_MB
    except (TypeError, ValueError):
        ok = False
    if ok:
        return None
    return (
        f"{key}={value} must be at least {MIN_MEMORY_LIMIT_MB} (MB; null: "
        f"{DEFAULT_MEMORY_LIMIT_MB})"
    )


# The longest time limit a key may set: the planner's wall-clock guard (1.25 x its limit +
# 15 s) must fit the operating system's poll() timeout (2**31 - 1 ms, about 24.8 days).
MAX_SECONDS = 1_000_000


def seconds(optional: bool = False) -> Check:
    """A time limit: a finite number of seconds, > 0 and at most :data:`MAX_SECONDS`
    (``optional``: or null, no limit)."""

    def check(key: str, value: Any) -> str | None:
        if value is None and optional:
            return None
        try:
            number = float(value)
        except (TypeError, ValueError):
            return f"{key}={value} must be a number > 0"
        if not number > 0:
            return f"{key}={value} must be > 0"
        if not math.isfinite(number) or number > MAX_SECONDS:
            return f"{key}={value} is too large (allowed: > 0 and at most {MAX_SECONDS} seconds)"
        return None

    return check


def between(low: float, high: float, low_open: bool = False, optional: bool = False) -> Check:
    """A finite number from ``low`` (excluded when ``low_open``) to ``high`` (``optional``:
    or null)."""

    def check(key: str, value: Any) -> str | None:
        if value is None and optional:
            return None
        try:
            number = float(value)
        except (TypeError, ValueError):
            number = math.nan
        above = number > low if low_open else number >= low
        if math.isfinite(number) and above and number <= high:
            return None
        lowest = f"> {low:g}" if low_open else f"{low:g}"
        return (
            f"{key}={value} is out of range (allowed: {lowest} to {high:g}{' or null' * optional})"
        )

    return check


def _not_a_key(key: str, value: Any) -> str | None:
    from twostep.llm.client import key_env_problem

    problem = key_env_problem(None if value is None else str(value))
    return None if problem is None else worded(problem)


def _score_modes() -> Iterable[str]:
    from twostep.makespan.model import MODES

    return MODES


def _llm_modes() -> Iterable[str]:
    from twostep.llm.client import MODES

    return MODES


def _translators() -> Iterable[str]:
    from twostep.llm.client import TRANSLATORS

    return TRANSLATORS


def _methods() -> Iterable[str]:
    from twostep.methods.registry import METHODS

    return METHODS


def _decomposers() -> Iterable[str]:
    from twostep.methods.registry import DECOMPOSERS

    return DECOMPOSERS


def _cuts() -> Iterable[str]:
    from twostep.dealing import CUTS
    from twostep.methods.plan_deal import BEST

    return (*CUTS, BEST)


def _log_levels() -> Iterable[str]:
    return ("DEBUG", "INFO", "WARNING", "ERROR", "CRITICAL")


@dataclass(frozen=True)
class Rule:
    """The allowed values of one config key (``key``: dotted; ``shown``: its name in the
    message, default the key)."""

    key: str
    check: Check
    allowed: str  # what is allowed, as the docs' table of ranges says it (a test compares)
    shown: str = ""

    @property
    def name(self) -> str:
        return self.shown or self.key


SECONDS = "> 0, at most 1000000 (seconds)"
VALUE_RULES: tuple[Rule, ...] = (
    Rule("score_mode", one_of(_score_modes), "exact, paper"),
    Rule("method.name", one_of(_methods), "the methods' names", "method"),
    Rule("decomposer.name", one_of(_decomposers, True), "the decomposers' names", "decomposer"),
    Rule("decomposer.cut", one_of(_cuts), "free, holding, mover, best"),
    Rule("decomposer.link_degree", at_least(0), ">= 0"),
    Rule("llm.mode", one_of(_llm_modes), "live, replay, scripted"),
    Rule("llm.translator", one_of(_translators), "llm, rules"),
    Rule("agents", at_least(1), ">= 1"),
    Rule("seed", at_least(0), ">= 0"),
    Rule("planner.time_limit_s", seconds(), SECONDS),
    Rule("planner.memory_limit_mb", memory_mb, ">= 64 (MB), or null (4096)"),
    Rule("planner.grounding_time_limit_s", seconds(optional=True), f"{SECONDS}, or null"),
    Rule("llm.timeout_s", seconds(), SECONDS),
    Rule("llm.max_retries", at_least(0), ">= 0"),
    Rule("llm.backoff_s", between(0, MAX_SECONDS), "0 to 1000000 (seconds)"),
    Rule("llm.temperature", between(0, 2), "0 to 2"),
    Rule("llm.top_p", between(0, 1, low_open=True, optional=True), "> 0 to 1, or null"),
    Rule("llm.max_tokens", at_least(1), ">= 1"),
    Rule("llm.api_key_env", _not_a_key, "a variable's name, never a key"),
    Rule("executor.max_steps", at_least(1, optional=True), ">= 1, or null"),
    Rule("executor.stall_limit", at_least(1), ">= 1"),
    Rule("executor.backoff_radius", at_least(1), ">= 1"),
    Rule("score_max_nodes", at_least(0, optional=True, hint=" (or null)"), ">= 0, or null"),
    Rule("score_time_limit_s", seconds(optional=True), f"{SECONDS}, or null"),
    Rule("mlflow.connect_timeout_s", seconds(), SECONDS),
    Rule("orchestration.server_startup_timeout_s", seconds(), SECONDS),
    Rule("orchestration.dask_workers", at_least(1), ">= 1"),
    Rule("orchestration.prefect_log_level", one_of(_log_levels), ", ".join(_log_levels())),
)


def rule_applies(rule: Rule, cfg: Any) -> bool:
    """Whether the job reads the rule's key (``decomposer.*`` only TwoStep does)."""
    if rule.key.startswith("decomposer."):
        from twostep.methods.registry import reads_subgoals

        return reads_subgoals(str(cfg.method.name))
    return True


def value_problems(cfg: Any, keys: Collection[str] | None = None) -> list[str]:
    """Every value of a job config out of its range (an empty list: all fine); ``keys``:
    only the rules of those dotted keys."""
    from omegaconf import OmegaConf

    problems = []
    for rule in VALUE_RULES:
        if keys is not None and rule.key not in keys:
            continue
        if not rule_applies(rule, cfg):
            continue
        if OmegaConf.is_config(cfg):
            value = OmegaConf.select(cfg, rule.key)
        else:
            value = _dotted(cfg, rule.key)
        problem = rule.check(rule.name, value)
        if problem:
            problems.append(problem)
    return problems


def _dotted(cfg: Any, key: str) -> Any:
    for part in key.split("."):
        cfg = cfg[part] if isinstance(cfg, Mapping) else getattr(cfg, part)
    return cfg


def check_values(cfg: Any) -> None:
    """Raise :class:`JobError` naming the first bad value, before any planning."""
    problems = value_problems(cfg)
    if problems:
        raise JobError(problems[0])


def input_problem(cfg: Any) -> str | None:
    """What makes a job's config unable to run, found without reading its task (None:
    nothing): a value out of range, or a data root, domain or task that is not there."""
    from twostep.tasks.benchmark import BenchmarkError, task_path

    problems = value_problems(cfg)
    if problems:
        return problems[0]
    try:
        task_path(str(cfg.domain.name), int(cfg.task), Path(str(cfg.data.root)))
    except BenchmarkError as error:
        return str(error)
    return None


def sweep_values(config: Any) -> dict[str, list[Any]]:
    """Every value a multirun lists per key (the sweeper's parameters, then the command
    line: a later value of a key replaces an earlier one, as in the sweeper), parsed with
    Hydra's override parser; keys without a sweep have their one value."""
    from hydra.core.override_parser.overrides_parser import OverridesParser

    params = config.hydra.sweeper.get("params") or {}
    arguments = [f"{k}={v}" for k, v in params.items()]
    arguments += [str(o) for o in config.hydra.overrides.task]
    values: dict[str, list[Any]] = {}
    for override in OverridesParser.create().parse_overrides(arguments):
        if override.is_delete():
            continue
        key = override.key_or_group
        sweep = override.is_sweep_override()
        values[key] = list(override.sweep_iterator()) if sweep else [override.value()]
    return values


def _domain_name(option: str) -> str:
    """The ``name`` a domain option's YAML sets (the option's own name when it cannot
    be read: a config of the user's own folder, say)."""
    from importlib import resources

    import yaml

    try:
        text = (resources.files("flows.conf") / "domain" / f"{option}.yaml").read_text()
        data = yaml.safe_load(text)
    except (OSError, ValueError, yaml.YAMLError):
        return option
    name = data.get("name") if isinstance(data, dict) else None
    return str(name) if name else option


def sweep_problem(config: Any) -> str | None:
    """The first value a multirun lists that a job could not run with (None: none), found
    before the sweep starts: each listed value of a key with a rule, set on the sweep's
    config (which holds every key's single value), and every (domain, task, data root) of
    the grid. Cheap: no job config is composed."""
    from omegaconf import OmegaConf
    from omegaconf.errors import OmegaConfBaseException

    from twostep.tasks.benchmark import BenchmarkError, task_path

    try:
        values = sweep_values(config)
    except Exception:  # another sweeper's syntax: each job checks its own values
        return None
    base = config
    rules = {rule.key: rule for rule in VALUE_RULES}
    groups = {"method": "method.name", "decomposer": "decomposer.name"}
    for key, listed in values.items():
        dotted = groups.get(key, key)
        rule = rules.get(dotted)
        if key.startswith("hydra") or (rule is None and key != "task"):
            continue
        for value in listed:
            if rule is not None and key in groups:  # a group's option names the value
                problem = rule.check(rule.name, value)
            else:
                job = copy.deepcopy(base)  # typed as the schema says
                try:  # the schema's type (agents=two)
                    OmegaConf.update(job, dotted, value)
                except OmegaConfBaseException as error:
                    return f"{key}={value}: {str(error).splitlines()[0]}"
                problem = next(iter(value_problems(job, {dotted})), None) if rule else None
            if problem:
                return problem
    domains = [_domain_name(str(d)) for d in values.get("domain", [])] or [str(base.domain.name)]
    tasks = values.get("task", [base.task])
    roots = values.get("data.root", [base.data.root])
    for domain in domains:
        for task in tasks:
            for root in roots:
                try:
                    task_path(domain, int(task), Path(str(root)))
                except (BenchmarkError, ValueError) as error:
                    return str(error)
    return None


def secret_problem(cfg: Any) -> str | None:
    """A key pasted where a variable's name belongs (``llm.api_key_env``) or into a name
    (``llm.model``), in the config or in any value a sweep's override lists: refused
    before Hydra writes the config and the overrides to disk. The message never repeats
    the value."""
    from hydra.core.override_parser.overrides_parser import OverridesParser

    from twostep.llm.client import key_env_problem, model_problem

    checks = {"llm.api_key_env": key_env_problem, "llm.model": model_problem}
    values: list[tuple[str, Any]] = [
        ("llm.api_key_env", cfg.llm.api_key_env),
        ("llm.model", cfg.llm.model),
    ]
    overrides = [str(o) for o in cfg.hydra.overrides.task] if "hydra" in cfg else []
    named = [o for o in overrides if o.lstrip("+~").split("=", 1)[0] in checks]
    try:
        for override in OverridesParser.create().parse_overrides(named):
            sweep = override.is_sweep_override()
            listed = list(override.sweep_iterator()) if sweep else [override.value()]
            values += [(override.key_or_group, value) for value in listed]
    except Exception:  # Hydra refuses the override itself, with its own message
        pass
    for key, value in values:
        problem = checks[key](None if value is None else str(value))
        if problem:
            return worded(problem)
    return None


# ----------------------------------------------------------------- writable locations


def writable_locations(cfg: Any, run_dir: Path | None = None) -> list[tuple[str, Path]]:
    """(what, folder) for every place a run of this config writes to; ``run_dir``: the
    Hydra run or sweep directory (not created yet when the callback asks)."""
    locations: list[tuple[str, Path]] = [
        ("output.root", Path(str(cfg.output.root))),
        ("orchestration.job_store", Path(str(cfg.orchestration.job_store))),
    ]
    if run_dir is not None:
        locations.append(("the run directory", run_dir))
    if cfg.mlflow.enabled:
        for key, uri in (
            ("mlflow.tracking_uri", cfg.mlflow.tracking_uri),
            ("mlflow.artifact_location", cfg.mlflow.artifact_location),
        ):
            folder = local_folder(None if uri is None else str(uri))
            if folder is not None:
                locations.append((key, folder))
    return locations


# What ends the path part of an address: MLflow's database and artifact addresses are
# built from output.root (conf/config.yaml), and SQLAlchemy and urllib read a '?' as the
# start of options (``mode=ro/out/mlflow.db``) and a '#' as a fragment.
URL_BREAKING = "?#"


def address_problem(cfg: Any) -> str | None:
    """A folder name that a legal path may hold but an MLflow address built from it
    cannot (None: none): one line naming the key and the character."""
    if not cfg.mlflow.enabled:
        return None
    root = str(cfg.output.root)
    for key in ("tracking_uri", "artifact_location"):
        uri = cfg.mlflow.get(key)
        if uri is None or root not in str(uri):
            continue
        bad = sorted({c for c in root if c in URL_BREAKING})
        if bad:
            shown = " or ".join(f"'{c}'" for c in bad)
            return (
                f"output.root {root} holds {shown}, which MLflow's address "
                f"(mlflow.{key}) cannot hold (the address ends there: what follows is read as "
                "options or a fragment); choose a "
                "folder without it, or set mlflow.tracking_uri and "
                "mlflow.artifact_location yourself (or mlflow.enabled=false)"
            )
    return None


def check_writable(cfg: Any, run_dir: Path | None = None) -> None:
    """Raise :class:`ValidationError` naming the first location that cannot be written."""
    problem = address_problem(cfg)
    if problem:
        raise ValidationError(problem)
    for key, folder in writable_locations(cfg, run_dir):
        problem = write_problem(folder)
        if problem:
            raise ValidationError(
                f"{key} {folder} is not writable ({problem}): choose another "
                "location (e.g. output.root=<folder>) or fix its permissions"
            )
