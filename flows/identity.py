"""Job identity: which config keys say *what* a job computes, its key, its names, and
which results are kept.

The one owner of these rules, on the config's side of the house (the library never sees
a config: :mod:`flows.build` turns one into library objects). The job store
(:mod:`flows.store`), the sweep's identity (:mod:`flows.sweep_state`), the job names on the
console and in MLflow, the params MLflow records (:mod:`flows.tracking.contents`) and the
report's series (:data:`flows.report_sources.RUN_PARAMS`) all ask this module.

* A config key is **not identity** when it only says where or how a job runs
  (:data:`NOT_IDENTITY_GROUPS`, :data:`NOT_IDENTITY_KEYS`), or when the job's method
  never reads it (:func:`is_relevant`: ``decomposer.*`` only matters to TwoStep,
  ``llm.*`` only to TwoStep with the LLM decomposer).
* The **job key** hashes the identity config, :data:`JOB_VERSION` and the content of
  every file the job reads (:func:`job_input_files`): editing a problem file, an expert
  subgoal file, an LLM script or a prompt gives a new key, so the job is computed again;
  a re-run with unchanged inputs finds the stored result.
* A result is **stored** (reused by later runs) unless its status says the job did not
  finish its work (:func:`is_storable`): a re-run tries those again; a stored entry is
  reused only when it is a whole, consistent result (:func:`result_problem`).

Plain data in, plain data out; the only I/O is reading the input files' bytes (through
:func:`twostep.util.files.read_input_bytes`).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

import twostep
from twostep.util.files import NotTextError, read_input_bytes
from twostep.util.outcome import RunStatus, storable

# Bump when a change to the pipeline makes stored results stale.
# job-3: the methods moved into twostep/methods (one request, enums, typed SA time)
# job-4: an embodied execution that fails fails the run (status embodied_failed)
JOB_VERSION = "job-4"

# Config groups (top-level keys) that say where or how a job runs. ``experiment`` only
# selects values for other keys, which are in the config themselves.
NOT_IDENTITY_GROUPS: tuple[str, ...] = ("hydra", "output", "mlflow", "orchestration", "experiment")

# Single keys that change how an answer is obtained or shown, never which answer.
# ``planner.grounding_time_limit_s``: a grounding it stops fails the job (status
# ``resource_limit``), which is never stored, so no stored result depends on it.
NOT_IDENTITY_KEYS: frozenset[str] = frozenset(
    {"llm.cache_dir", "llm.max_retries", "llm.backoff_s", "llm.api_key_env", "executor.render",
     "planner.grounding_time_limit_s"}
)  # fmt: skip

# Keys added after jobs were stored, at the value that computes what those jobs computed:
# left out of the identity, so that the stored jobs keep their keys.
NEUTRAL_VALUES: dict[str, Any] = {"llm.bundle": None, "llm.translator": "llm"}

# What every result has (``RunResult.to_dict``): a stored entry without them is no result.
RESULT_KEYS: frozenset[str] = frozenset({"domain", "task", "method", "agents", "success", "status"})

_PROMPTS = Path(twostep.__file__).resolve().parent / "prompts"  # the LLM prompts' templates


def is_identity_key(name: str) -> bool:
    """Whether the dotted config key (or command-line override key) can change a result.

    ``hydra/launcher`` (a group override), ``+orchestration.x`` and ``~mlflow.y`` are
    understood as well.
    """
    name = name.lstrip("+~")
    head = name.replace("/", ".").split(".", 1)[0]
    return head not in NOT_IDENTITY_GROUPS and name not in NOT_IDENTITY_KEYS


def is_sweep_identity_key(name: str) -> bool:
    """Whether a sweep's override names what the sweep computes (its MLflow experiment
    and parent run). Unlike a job, a sweep is named by the experiment that selects its
    grid (``experiment=paper``), not by the grid it expands to."""
    return name.lstrip("+~").replace("/", ".").split(".", 1)[0] == "experiment" or (
        is_identity_key(name)
    )


def is_relevant(name: str, method: str | None, decomposer: str | None) -> bool:
    """Whether a job of ``method`` (and ``decomposer``) reads the dotted key ``name``.

    ``None`` means unknown: everything is relevant.
    """
    if method is None:
        return True
    if name.startswith("decomposer."):
        return method == "twostep"
    if name.startswith("llm."):
        return method == "twostep" and decomposer in (None, "llm")
    return True


def _method_of(config: Mapping[str, Any]) -> tuple[str | None, str | None]:
    method, decomposer = config.get("method"), config.get("decomposer")
    method_name = method.get("name") if isinstance(method, Mapping) else method
    decomposer_name = decomposer.get("name") if isinstance(decomposer, Mapping) else decomposer
    return (
        None if method_name is None else str(method_name),
        None if decomposer_name is None else str(decomposer_name),
    )


def identity_config(config: Mapping[str, Any]) -> dict[str, Any]:
    """The part of a resolved config that decides what the job computes."""
    method, decomposer = _method_of(config)

    def keep(data: Mapping[str, Any], prefix: str) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for key, value in data.items():
            name = f"{prefix}{key}"
            if not is_identity_key(name) or not is_relevant(name + ".", method, decomposer):
                continue
            if name in NEUTRAL_VALUES and value == NEUTRAL_VALUES[name]:
                continue
            out[str(key)] = keep(value, f"{name}.") if isinstance(value, Mapping) else value
        return out

    return keep(config, "")


def job_input_files(config: Mapping[str, Any], problem_path: Path | None) -> dict[str, Path]:
    """Every file the job reads, by role: the job key hashes their content.

    ``problem_path`` is the task's problem file (``None``: unknown, e.g. no such task).
    """
    from twostep.tasks.benchmark import domain_file  # the rule of which domain file a task reads

    method, decomposer = _method_of(config)
    data = config.get("data")
    root = Path(str(data.get("root", "data"))) if isinstance(data, Mapping) else Path("data")
    domain = config.get("domain")
    domain_name = str(domain.get("name", "")) if isinstance(domain, Mapping) else str(domain)
    folder = root / domain_name
    files: dict[str, Path] = {"domain": domain_file(domain_name, root)}
    if problem_path is not None:
        files["problem"] = problem_path
    if method == "twostep" and decomposer == "expert":
        files["expert"] = folder / "expert.yaml"
    if method == "twostep" and decomposer == "llm":
        # The prompts show the task and the domain's example in English.
        if problem_path is not None:
            files["problem_nl"] = problem_path.with_suffix(".nl")
        for name in ("domain.nl", "p_example.nl", "p_example.pddl", "p_example.sol"):
            files[name] = folder / name
        llm = config.get("llm")
        script = llm.get("script") if isinstance(llm, Mapping) else None
        if script:
            files["llm_script"] = Path(str(script))
        bundle = llm.get("bundle") if isinstance(llm, Mapping) else None
        if bundle:  # the replayed answers (twostep.replay.bundle.BUNDLE_FILE)
            folder = Path(str(bundle))
            files["llm_bundle"] = folder if folder.suffix == ".json" else folder / "bundle.json"
        for prompt in sorted(_PROMPTS.glob("*.txt")):
            files[f"prompt:{prompt.name}"] = prompt
    kitchen = _kitchen_file(config, problem_path.parent if problem_path else folder)
    if kitchen is not None:
        files["kitchen"] = kitchen
    return files


def _kitchen_file(config: Mapping[str, Any], folder: Path) -> Path | None:
    """The floor plan an embodied job reads: its task folder's ``kitchen.yaml`` when no
    ``executor.layout`` names a scene (the rule of
    :func:`twostep.embodied.layouts.floor_plan_for_task`); None for a symbolic job, a
    named scene, or a folder without one (the scene comes with the alfworld wheel)."""
    executor = config.get("executor")
    if not isinstance(executor, Mapping) or str(executor.get("name")) != "embodied":
        return None
    if executor.get("layout") is not None:
        return None
    from twostep.embodied.floorplan import FLOOR_PLAN_FILE
    from twostep.util.files import exists

    path = folder / FLOOR_PLAN_FILE
    return path if exists(path) else None


def file_digest(path: Path) -> str:
    """SHA-256 of a file's bytes, read by the one checked reader of input files
    (:func:`twostep.util.files.read_input_bytes`: a FIFO is never waited on, ``/dev/zero``
    never read); ``"missing"`` for a file that cannot be read (the job's check before any
    work names it)."""
    try:
        return hashlib.sha256(read_input_bytes(Path(path))).hexdigest()
    except (OSError, NotTextError):
        return "missing"


def code_version() -> str:
    """The installed package version (part of every job key)."""
    try:
        return metadata.version("twostep")
    except metadata.PackageNotFoundError:
        return "unknown"


def job_key(config: Mapping[str, Any], inputs: Mapping[str, str] | None = None) -> str:
    """Stable hash of what the job computes (``twostep.job_key`` in MLflow).

    ``inputs``: digest of each input file by role (:func:`input_digests`).
    """
    blob = json.dumps(
        {
            "version": JOB_VERSION,
            "code": code_version(),
            "config": identity_config(config),
            "inputs": dict(sorted((inputs or {}).items())),
        },
        sort_keys=True,
        default=str,
    )
    return hashlib.sha256(blob.encode()).hexdigest()[:32]


def input_digests(files: Mapping[str, Path]) -> dict[str, str]:
    return {role: file_digest(path) for role, path in files.items()}


def is_storable(result: Mapping[str, Any]) -> bool:
    """Whether a finished job's result may be reused by later runs."""
    return storable(result.get("status")) and "error" not in result


def is_complete_result(result: Mapping[str, Any]) -> bool:
    """Whether a stored entry is the whole result of a finished job (an emptied, cut or
    hand-edited entry is not: the job is computed again)."""
    return result_problem(result) is None


def result_problem(result: Mapping[str, Any]) -> str | None:
    """Why a stored entry is not the whole, consistent result of a finished job (None: it
    is): every key of :data:`RESULT_KEYS`, a status that is stored, and a success that
    says so throughout (status ``solved``, its plans, an execution length, a schedule of
    that many steps holding every planned action)."""
    missing = sorted(RESULT_KEYS - set(result))
    if missing:
        return f"no {', '.join(missing)}"
    if not isinstance(result.get("success"), bool):
        return "'success' is neither true nor false"
    status = str(result.get("status"))
    if not is_storable(result):
        return f"status '{status}' is never stored"
    if not result["success"]:
        return "a failure with status 'solved'" if status == RunStatus.SOLVED else None
    if status != RunStatus.SOLVED:  # the status of every success
        return f"a success with status '{status}'"
    plans = result.get("plans")
    if not isinstance(plans, Mapping) or not all(
        isinstance(steps, list) and all(isinstance(step, str) for step in steps)
        for steps in plans.values()
    ):
        return "a success without its plans"
    length = result.get("exec_length")
    if isinstance(length, bool) or not isinstance(length, int) or length < 0:
        return "a success without its execution length"
    schedule = result.get("schedule")
    if not isinstance(schedule, list) or len(schedule) != length:
        return f"a success whose schedule is not {length} steps long (its exec_length)"
    planned = sum(len(steps) for steps in plans.values())
    scheduled = sum(len(step) if isinstance(step, list) else 0 for step in schedule)
    if planned != scheduled:
        return f"a success whose schedule holds {scheduled} actions, its plans {planned}"
    return None


def config_seed_matters(config: Mapping[str, Any]) -> bool:
    """:func:`twostep.methods.result.seed_matters` of a job's config (imported here, in a
    job's process: the methods are loaded there anyway)."""
    from twostep.methods.result import seed_matters

    method, decomposer = _method_of(config)
    return seed_matters(method, decomposer, _name_of(config.get("executor")))


def _task_text(task: Any) -> str:
    return f"{task:02d}" if isinstance(task, int) else str(task)


def _name_of(value: Any) -> Any:
    return value.get("name") if isinstance(value, Mapping) else value


def job_name(config: Mapping[str, Any]) -> str:
    """The job's one name, on the console, in Prefect and in MLflow, from its config or
    its result.json dict: domain, task, method, decomposer (TwoStep), the N the job runs
    and the seed, e.g. ``grippers-p09-twostep-goal-split-n2-s0``. SA runs one agent: it is
    ``-n1-`` whatever ``agents`` says (a sweep over ``agents=2,3`` runs it once per N
    value, under one name; MLflow's tag ``twostep.grid_agents`` tells them apart)."""
    method = _name_of(config.get("method"))
    decomposer = _name_of(config.get("decomposer")) if method == "twostep" else None
    runs = 1 if method == "sa" else config.get("agents")
    return (
        f"{_name_of(config.get('domain'))}-p{_task_text(config.get('task'))}-{method}"
        f"{f'-{decomposer}' if decomposer else ''}-n{runs}-s{config.get('seed')}"
    )
