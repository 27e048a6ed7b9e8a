"""A replay bundle: real model answers with their provenance, and the numbers logged with them.

A bundle is a folder holding ``bundle.json`` (:data:`BUNDLE_FILE`), written whole by the
importer (``twostep-data import-answers``). It holds

* **runs** (:class:`Run`): one per imported log file and run label, with the model the
  user named, the file's name, path and SHA-256;
* **entries** (:class:`Entry`): per run, domain, task and number of agents N, the model's
  answers for helpers 1..N-1 (:class:`Answer`: the text and the log line), the model's own
  PDDL translations when the log shows them, and the official code's numbers
  (:class:`OfficialNumbers`);
* **tasks**: optionally the SHA-256 of each task file the answers refer to, so that a
  replay on other files (twostep's own ``data/``, whose objects differ) is refused.

Which run answers a job: the runs of the job's model that hold answers for its domain and
N, in the order they were imported; the job's seed picks one (seed 0 the first), as the
paper's three runs are three seeds. :meth:`Bundle.entry` raises :class:`BundleMiss` naming
what is missing: never a fallback that would look like a result.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from twostep.util.files import NotTextError, read_input_bytes, read_text_file, write_json_atomic

BUNDLE_FILE = "bundle.json"
BUNDLE_FORMAT = "twostep-replay-bundle"
BUNDLE_VERSION = 1


class BundleError(ValueError):
    """A bundle that cannot be read or written (the message names the file)."""


class BundleMiss(LookupError):
    """The bundle holds no answer for what a job asks (domain, task, N, model, seed)."""


@dataclass(frozen=True)
class Answer:
    """One helper's answer as the model gave it, and the log line it comes from."""

    helper: int  # 1-based
    text: str
    line: int


@dataclass(frozen=True)
class OfficialNumbers:
    """What the official code logged for one task and N (None: not in the log).

    ``helper_costs[i]`` is the cost of helper i+1's plan for the model's own translation
    (None: not logged, or no plan: ``helper_no_plan`` lists the helpers whose planner call
    the log says found none); ``exec_length`` is the official code's multi-agent execution
    length, ``sa_cost`` its single-agent plan cost (anytime LAMA).
    """

    sa_cost: float | None = None
    sa_time_s: float | None = None
    helper_costs: tuple[float | None, ...] = ()
    helper_no_plan: tuple[int, ...] = ()
    helper_times_s: tuple[float | None, ...] = ()
    main_cost: float | None = None
    exec_length: float | None = None
    planning_time_s: float | None = None
    valid: bool | None = None  # the official validation of its joint execution

    def to_dict(self) -> dict[str, Any]:
        data = asdict(self)
        data["helper_costs"] = list(self.helper_costs)
        data["helper_no_plan"] = list(self.helper_no_plan)
        data["helper_times_s"] = list(self.helper_times_s)
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> OfficialNumbers:
        return cls(
            sa_cost=data.get("sa_cost"),
            sa_time_s=data.get("sa_time_s"),
            helper_costs=tuple(data.get("helper_costs") or ()),
            helper_no_plan=tuple(int(h) for h in data.get("helper_no_plan") or ()),
            helper_times_s=tuple(data.get("helper_times_s") or ()),
            main_cost=data.get("main_cost"),
            exec_length=data.get("exec_length"),
            planning_time_s=data.get("planning_time_s"),
            valid=data.get("valid"),
        )


@dataclass(frozen=True)
class Run:
    """One run of the official code: a log file (and its run label), one model."""

    id: str
    model: str
    file: str  # the log's file name
    path: str  # where it was read from
    sha256: str
    label: str | None = None  # the run number its TASK lines name
    format: str = "twostep-official"

    def where(self, line: int | None = None) -> str:
        return f"{self.file}:{line}" if line is not None else self.file


@dataclass(frozen=True)
class Entry:
    """A run's answers for one task and N, with the official numbers of that task."""

    run: str
    domain: str
    task: int
    agents: int
    line: int  # the line of the answers
    answers: tuple[Answer, ...]
    official: OfficialNumbers = field(default_factory=OfficialNumbers)
    translations: tuple[str | None, ...] = ()  # the model's PDDL, when the log shows it

    @property
    def key(self) -> tuple[str, int, int]:
        return (self.domain, self.task, self.agents)

    def to_dict(self) -> dict[str, Any]:
        return {
            "run": self.run,
            "domain": self.domain,
            "task": self.task,
            "agents": self.agents,
            "line": self.line,
            "answers": [asdict(a) for a in self.answers],
            "translations": list(self.translations),
            "official": self.official.to_dict(),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Entry:
        return cls(
            run=str(data["run"]),
            domain=str(data["domain"]),
            task=int(data["task"]),
            agents=int(data["agents"]),
            line=int(data["line"]),
            answers=tuple(
                Answer(int(a["helper"]), str(a["text"]), int(a["line"])) for a in data["answers"]
            ),
            official=OfficialNumbers.from_dict(data.get("official") or {}),
            translations=tuple(data.get("translations") or ()),
        )


def same_model(asked: str, recorded: str) -> bool:
    """Whether ``asked`` (the model a job asks for: ``LLMSettings.model``) names the model
    the answers were imported for (``openai/gpt-4o`` and ``gpt-4o`` are the same model)."""
    return asked == recorded or asked.split("/", 1)[-1] == recorded.split("/", 1)[-1]


def task_name(domain: str, task: int) -> str:
    return f"{domain}/p{task:02d}"


@dataclass
class Bundle:
    """The runs and entries of a bundle (see the module docstring)."""

    runs: list[Run] = field(default_factory=list)
    entries: list[Entry] = field(default_factory=list)
    tasks: dict[str, str] = field(default_factory=dict)  # "barman/p01" -> SHA-256
    path: Path | None = None

    def __post_init__(self) -> None:
        self._index: dict[tuple[str, str, int, int], Entry] = {
            (e.run, e.domain, e.task, e.agents): e for e in self.entries
        }

    # ------------------------------------------------------------------ reading

    @property
    def models(self) -> list[str]:
        return list(dict.fromkeys(run.model for run in self.runs))

    def run(self, run_id: str) -> Run:
        return next(r for r in self.runs if r.id == run_id)

    def runs_for(self, domain: str, agents: int, model: str) -> list[Run]:
        """The runs of ``model`` with answers for ``domain`` at ``agents``, in import order
        (seed 0 replays the first)."""
        used = {e.run for e in self.entries if e.domain == domain and e.agents == agents}
        return [r for r in self.runs if r.id in used and same_model(model, r.model)]

    def has(self, run_id: str, domain: str, task: int, agents: int) -> bool:
        """Whether run ``run_id`` holds answers for that task and N."""
        return (run_id, domain, task, agents) in self._index

    def cells(self) -> list[tuple[str, int, int]]:
        """Every (domain, task, N) with answers, sorted."""
        return sorted({e.key for e in self.entries})

    def entry(self, domain: str, task: int, agents: int, model: str, seed: int = 0) -> Entry:
        """The answers replayed for a job; :class:`BundleMiss` says what is missing."""
        where = f"{self.path or 'the bundle'}"
        if not any(same_model(model, m) for m in self.models):
            raise BundleMiss(
                f"{where} holds no answers of model '{model}' "
                f"(models: {', '.join(self.models) or 'none'}; set LLMSettings.model)"
            )
        runs = self.runs_for(domain, agents, model)
        if not runs:
            have = sorted({e.agents for e in self.entries if e.domain == domain})
            domains = sorted({e.domain for e in self.entries})
            detail = (
                f"N = {', '.join(map(str, have))}"
                if have
                else f"domains: {', '.join(domains) or 'none'}"
            )
            raise BundleMiss(
                f"{where} has no answers of {model} for {domain} with {agents} agents ({detail})"
            )
        if not 0 <= seed < len(runs):
            raise BundleMiss(
                f"{where} has {len(runs)} run(s) of {model} answers for {domain} with "
                f"{agents} agents; seed {seed} asks for run {seed + 1} (seeds 0..{len(runs) - 1})"
            )
        run = runs[seed]
        found = self._index.get((run.id, domain, task, agents))
        if found is None:
            tasks = sorted(
                e.task
                for e in self.entries
                if e.run == run.id and e.domain == domain and e.agents == agents
            )
            raise BundleMiss(
                f"{where}: run {run.id} ({run.file}) has no answers for {task_name(domain, task)} "
                f"with {agents} agents (its {domain} tasks at N={agents}: "
                f"{', '.join(f'p{t:02d}' for t in tasks)})"
            )
        return found

    def task_digest(self, domain: str, task: int) -> str | None:
        return self.tasks.get(task_name(domain, task))

    def check_task_file(self, domain: str, task: int, problem_path: Path) -> None:
        """:class:`BundleMiss` when the bundle recorded the task file its answers refer to
        and ``problem_path`` is another file (the answers name objects of that one)."""
        recorded = self.task_digest(domain, task)
        if recorded is None:
            return
        try:
            digest = hashlib.sha256(read_input_bytes(Path(problem_path))).hexdigest()
        except (OSError, NotTextError):
            digest = "missing"
        if digest != recorded:
            raise BundleMiss(
                f"{problem_path} is not the task file the bundle's answers for "
                f"{task_name(domain, task)} refer to (imported with --tasks): point "
                "load_task(root=...) at the folder the answers were given for"
            )

    # ------------------------------------------------------------------ writing

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": BUNDLE_FORMAT,
            "version": BUNDLE_VERSION,
            "runs": [asdict(r) for r in self.runs],
            "tasks": dict(sorted(self.tasks.items())),
            "entries": [e.to_dict() for e in self.entries],
        }

    def save(self, folder: Path) -> Path:
        """Write ``folder/bundle.json`` atomically (a reader never sees half of it)."""
        path = Path(folder) / BUNDLE_FILE
        write_json_atomic(path, self.to_dict(), indent=1)
        self.path = Path(folder)
        return path

    @classmethod
    def from_dict(cls, data: Any, source: str = BUNDLE_FILE) -> Bundle:
        if not isinstance(data, dict) or data.get("format") != BUNDLE_FORMAT:
            raise BundleError(f"{source}: not a replay bundle (no format: {BUNDLE_FORMAT})")
        if data.get("version") != BUNDLE_VERSION:
            raise BundleError(
                f"{source}: bundle version {data.get('version')} is not {BUNDLE_VERSION}: "
                "import the logs again"
            )
        try:
            runs = [Run(**r) for r in data.get("runs") or []]
            entries = [Entry.from_dict(e) for e in data.get("entries") or []]
            tasks = {str(k): str(v) for k, v in (data.get("tasks") or {}).items()}
        except (KeyError, TypeError, ValueError) as error:
            raise BundleError(f"{source}: malformed bundle ({error})") from None
        return cls(runs=runs, entries=entries, tasks=tasks)


_LOADED: dict[tuple[str, float, int], Bundle] = {}


def load_bundle(folder: Path | str) -> Bundle:
    """The bundle in ``folder`` (a folder holding ``bundle.json``, or that file itself);
    :class:`BundleError` naming the file when it cannot be read. Read once per process
    while the file is unchanged (a sweep's jobs share it)."""
    path = Path(folder)
    if path.is_dir():
        path = path / BUNDLE_FILE
    if not path.is_file():
        raise BundleError(
            f"no replay bundle at {path} (make one with 'twostep-data import-answers')"
        )
    stat = path.stat()
    key = (str(path.resolve()), stat.st_mtime, stat.st_size)
    if key in _LOADED:
        return _LOADED[key]
    try:
        data = json.loads(read_text_file(path))
    except NotTextError as error:
        raise BundleError(str(error)) from None
    except ValueError as error:
        raise BundleError(f"{path}: not JSON ({error})") from None
    except OSError as error:
        raise BundleError(f"{path}: {error.strerror or error}") from None
    bundle = Bundle.from_dict(data, str(path))
    bundle.path = path.parent
    _LOADED[key] = bundle
    return bundle
