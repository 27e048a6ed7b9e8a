"""Benchmark tasks on disk in the LLM+P layout.

A data root holds one folder per domain::

    <root>/<domain>/domain.pddl  domain.nl
    <root>/<domain>/p01.pddl .. p20.pddl   p01.nl .. p20.nl
    <root>/<domain>/p_example.pddl  p_example.nl  p_example.sol
    <root>/<domain>/expert.yaml      (optional: hand-written helper subgoals)
    <root>/<domain>/titles.yaml      (optional: a one-line title per task, p01: "...")

:func:`load_task` reads one task (PDDL, its English description and the domain's example)
into a :class:`BenchmarkTask`. Any directory in this layout works, e.g. a checkout of the
LLM+P benchmark, whose files are read as they are.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from twostep.pddl import PDDLError, Problem, load_problem
from twostep.pddl.translator import GroundingLimits
from twostep.util.files import NotTextError, exists, file_problem, read_text_file, read_yaml_file


def _installed_data_root() -> Path:
    """The benchmark data installed with the package (``twostep.data``: the source tree's
    ``data/``, see pyproject.toml), wherever the process runs."""
    try:
        return Path(str(resources.files("twostep.data")))
    except ModuleNotFoundError:  # a source tree on sys.path that was never installed
        return Path(__file__).resolve().parents[2] / "data"


DEFAULT_DATA_ROOT = _installed_data_root()
_TASK_FILE = re.compile(r"^p(\d+)\.pddl$")


class BenchmarkError(Exception):
    """An unknown domain or task, or a data folder that is not in the expected layout."""


@dataclass(frozen=True)
class BenchmarkTask:
    """One task of a benchmark domain, with everything the prompts need."""

    domain_name: str
    task_id: int
    problem: Problem
    problem_path: Path
    domain_path: Path
    task_nl: str  # English description of this task (empty if the .nl file is missing)
    domain_nl: str
    example_nl: str  # the domain's in-context example task, in English
    example_plan: tuple[str, ...]  # ... and its single-agent plan
    example_pddl: str

    @property
    def name(self) -> str:
        return f"{self.domain_name}/p{self.task_id:02d}"


def _read(path: Path) -> str:
    """An optional text file of the task (none there: empty); one that cannot be read as
    text (binary, a FIFO, ...) is a :class:`BenchmarkError` naming it."""
    if not exists(path):
        return ""
    try:
        return read_text_file(path)
    except NotTextError as error:
        raise BenchmarkError(str(error)) from None


def load_pddl_files(
    domain_path: Path,
    problem_path: Path,
    cache_dir: Path | None = None,
    limits: GroundingLimits | None = None,
) -> Problem:
    """Read a domain and a problem file (:func:`twostep.pddl.load_problem`) so that every
    bad file is one :class:`PDDLError` naming it: also a directory where a file belongs,
    and expressions nested deeper than the reader can follow (Python's recursion limit)."""
    try:
        return load_problem(domain_path, problem_path, cache_dir, limits)
    except RecursionError:
        depth, line, path = max((*_deepest(Path(p)), Path(p)) for p in (domain_path, problem_path))
        raise PDDLError(
            f"expressions nested {depth} levels deep: deeper than the reader can follow "
            "(write the formula flatter, e.g. one (and ...) holding all its parts)",
            str(path),
            line,
        ) from None


def _deepest(path: Path) -> tuple[int, int]:
    """The deepest nesting of parentheses in a PDDL file, and its line (comments skipped)."""
    depth = deepest = deepest_line = 0
    for number, line in enumerate(path.read_bytes().decode("utf-8", "replace").splitlines(), 1):
        for char in line.split(";", 1)[0]:
            depth += {"(": 1, ")": -1}.get(char, 0)
            if depth > deepest:
                deepest, deepest_line = depth, number
    return deepest, deepest_line


def domain_file(domain: str, root: Path = DEFAULT_DATA_ROOT) -> Path:
    """The domain file of ``domain`` in ``root``: the folder's own ``domain.pddl``; for a
    folder of tasks without one (the LLM+P benchmark's blocksworld ships problems only),
    the domain of that name installed with twostep, which reads those tasks as they are."""
    folder = Path(root) / domain
    own = folder / "domain.pddl"
    shipped = DEFAULT_DATA_ROOT / domain / "domain.pddl"
    if own.exists() or not shipped.is_file() or not folder.is_dir():
        return own
    has_tasks = any(_TASK_FILE.match(p.name) and p.is_file() for p in folder.iterdir())
    return shipped if has_tasks else own


def list_domains(root: Path = DEFAULT_DATA_ROOT) -> list[str]:
    if not root.is_dir():
        raise BenchmarkError(f"data root {root} does not exist")
    return sorted(p.name for p in root.iterdir() if domain_file(p.name, root).is_file())


def list_tasks(domain: str, root: Path = DEFAULT_DATA_ROOT) -> list[int]:
    folder = domain_dir(domain, root)
    return sorted(
        int(m.group(1)) for p in folder.iterdir() if (m := _TASK_FILE.match(p.name)) and p.is_file()
    )


def domain_dir(domain: str, root: Path = DEFAULT_DATA_ROOT) -> Path:
    folder = Path(root) / domain
    problem = file_problem(folder / "domain.pddl")
    if problem is not None:  # a FIFO, a device, a directory, a symlink loop, too large
        raise BenchmarkError(problem)
    if not domain_file(domain, root).is_file():
        known = ", ".join(list_domains(Path(root))) or "none"
        raise BenchmarkError(f"unknown domain '{domain}' in {root}; domains: {known}")
    return folder


TITLES_FILE = "titles.yaml"


def task_titles(domain: str, root: Path = DEFAULT_DATA_ROOT) -> dict[int, str]:
    """The domain's one-line task titles (``titles.yaml``: ``p01: "..."``), by task id;
    empty when the folder has none."""
    path = domain_dir(domain, root) / TITLES_FILE
    if not exists(path):
        return {}
    try:
        data = read_yaml_file(path)
    except (NotTextError, ValueError, OSError) as error:  # FileFormatError is a ValueError
        raise BenchmarkError(str(error)) from None
    return parse_task_titles(data or {}, path)


def parse_task_titles(data: object, path: Path) -> dict[int, str]:
    """Task id -> title from a loaded ``titles.yaml`` (keys ``p01`` or ``1``: the task's
    file name or its number); a :class:`BenchmarkError` naming ``path`` for anything else."""
    if not isinstance(data, dict):
        raise BenchmarkError(f"{path}: expected p01: title lines")
    titles = {}
    for key, title in data.items():
        match = re.fullmatch(r"p?(\d+)", str(key))
        if match is None:
            raise BenchmarkError(f"{path}: '{key}' is not a task name (p01, p02, ...)")
        titles[int(match.group(1))] = " ".join(str(title).split())
    return titles


def task_path(domain: str, task: int, root: Path = DEFAULT_DATA_ROOT) -> Path:
    folder = domain_dir(domain, root)
    for candidate in (folder / f"p{task:02d}.pddl", folder / f"p{task}.pddl"):
        problem = file_problem(candidate)
        if problem is not None:  # a FIFO, a device, a directory, a symlink loop, too large
            raise BenchmarkError(problem)
        if candidate.is_file():
            return candidate
    tasks = list_tasks(domain, root)
    listing = f"{tasks[0]}..{tasks[-1]}" if tasks else "none"
    raise BenchmarkError(f"unknown task {task} of domain '{domain}'; tasks: {listing}")


def load_task(
    domain: str,
    task: int,
    root: Path = DEFAULT_DATA_ROOT,
    cache_dir: Path | None = None,
    limits: GroundingLimits | None = None,
) -> BenchmarkTask:
    """Load task ``task`` (1-based) of ``domain`` from the data root ``root``
    (``cache_dir``: parsed problems kept for the next process, see ``load_problem``;
    ``limits``: what its grounding may use, :class:`~twostep.pddl.translator.GroundingLimits`)."""
    root = Path(root)
    folder = domain_dir(domain, root)
    path = task_path(domain, task, root)
    domain_path = domain_file(domain, root)
    problem = load_pddl_files(domain_path, path, cache_dir, limits)
    plan_text = _read(folder / "p_example.sol")
    example_plan = tuple(
        line.split(";", 1)[0].strip()
        for line in plan_text.splitlines()
        if line.split(";", 1)[0].strip()
    )
    return BenchmarkTask(
        domain_name=domain,
        task_id=task,
        problem=problem,
        problem_path=path,
        domain_path=domain_path,
        task_nl=_read(path.with_suffix(".nl")).strip(),
        domain_nl=_read(folder / "domain.nl").strip(),
        example_nl=_read(folder / "p_example.nl").strip(),
        example_plan=example_plan,
        example_pddl=_read(folder / "p_example.pddl"),
    )


__all__ = [
    "DEFAULT_DATA_ROOT",
    "BenchmarkError",
    "BenchmarkTask",
    "PDDLError",
    "domain_dir",
    "domain_file",
    "list_domains",
    "list_tasks",
    "load_pddl_files",
    "load_task",
    "task_path",
]
