"""Reading tasks: files to the lifted model (our reader) and its grounding (the translator's).

:func:`parse_problem` checks the s-expressions (unbalanced parentheses: file and line),
applies the repairs real-world files need (:mod:`twostep.pddl.repairs`), reads the lifted
model (:mod:`twostep.pddl.lifted`) and, when the task's meaning needs it at once (derived
facts, a goal formula), grounds it with Fast Downward's translator
(:func:`ground_problem`); otherwise the grounding is made on first use.
:func:`load_problem` reads files, with an optional on-disk cache that holds the grounding.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import pickle
import sys
from dataclasses import replace
from importlib import metadata
from pathlib import Path

from twostep.pddl.errors import PDDLError
from twostep.pddl.goals import ground_goal
from twostep.pddl.grounded import Fact, GroundTask, fact_to_pddl
from twostep.pddl.lifted import conjunction_literals, read_domain, read_problem
from twostep.pddl.lint import check_kinds, lint_domain, lint_problem
from twostep.pddl.model import Goal, Problem, set_grounder
from twostep.pddl.repairs import repair_task
from twostep.pddl.sas import read_sas
from twostep.pddl.sexp import read_sexp, write_sexp
from twostep.pddl.translator import GroundingLimits, grounding_limits, translate
from twostep.pddl.writer import planner_input, pretty_define, problem_to_pddl
from twostep.programs.processes import ResourceLimitError
from twostep.util.files import NotAFileError, file_problem, read_input_bytes, write_bytes_atomic

UNREACHABLE_GOAL: Fact = ("@unreachable-goal",)
"""The fact a goal formula stands for when the translator finds it unreachable: no state
holds it (the name cannot be a PDDL predicate)."""


def parse_problem(
    domain_text: str,
    problem_text: str,
    domain_source: str | None = None,
    problem_source: str | None = None,
) -> Problem:
    """Parse a domain and a problem given as PDDL text (a UTF-8 byte-order mark is no part
    of the text)."""
    domain_text = domain_text.removeprefix("\ufeff")
    problem_text = problem_text.removeprefix("\ufeff")
    read_sexp(domain_text, domain_source, single=True)  # unbalanced parentheses: file and line
    read_sexp(problem_text, problem_source, single=True)
    domain_body, problem_body, repaired = repair_task(
        domain_text, problem_text, domain_source, problem_source
    )
    # line numbers come from the files as written (a repair only moves declarations)
    check_kinds(
        domain_body, problem_body, (domain_source, problem_source), (domain_text, problem_text)
    )
    domain = read_domain(domain_body, domain_text, domain_source)
    lint_domain(domain, domain_text, domain_source)  # types, arities, variables
    parts = read_problem(problem_body, domain, problem_text, problem_source)
    lint_problem(domain, parts, problem_body, problem_text, problem_source)
    if repaired:
        domain = replace(domain, text=pretty_define(domain_body))
        problem_text = pretty_define(problem_body)
    else:
        domain = replace(domain, text=domain_text)
    problem = Problem(
        parts.name,
        domain,
        parts.objects,
        parts.init,
        parts.goal,
        problem_source,
        numeric_init=parts.numeric_init,
        body=problem_body,
        text=problem_text,
    )
    if problem.needs_axioms:
        return with_grounding(problem)
    return problem


def with_grounding(problem: Problem) -> Problem:
    """``problem`` with its initial state closed and its goal formula's facts named."""
    task = problem.grounded
    goal = problem.goal
    if goal.formula is not None:
        facts = task.goal_positive or frozenset((UNREACHABLE_GOAL,))
        positive, negative, complete = goal.positive, goal.negative | task.goal_negative, False
        try:  # the one conjunction the static facts may leave
            literal = ground_goal([goal.formula], problem, problem.source or "goal")
            positive, negative, complete = literal.positive, literal.negative, True
        except PDDLError:
            pass
        goal = Goal(positive, negative, goal.formula, facts, complete)
    object.__setattr__(problem, "init", task.close(problem.init))
    object.__setattr__(problem, "goal", goal)
    return problem


def ground_problem(problem: Problem) -> GroundTask:
    """The translator's grounding of ``problem`` (see :mod:`twostep.pddl.translator`).

    A goal the translator finds unreachable leaves it no actions; the task is then
    grounded towards the empty goal (its goal facts: :data:`UNREACHABLE_GOAL`).
    """
    domain_text, problem_text = planner_input(problem)
    files = (
        f"{problem.source} (domain {problem.domain.source})"
        if problem.domain.source
        else problem.source
    )
    try:
        translation = translate(domain_text, problem_text)
    except PDDLError as error:  # the translator reads both files: name them
        if error.source is not None or problem.source is None:
            raise
        raise PDDLError(error.message, files) from None
    except ResourceLimitError as error:
        if problem.source is None:
            raise
        raise ResourceLimitError(error.reached.where(f"{files}: ")) from None
    if translation.goal_unreachable:
        open_goal = problem.with_state(goal=Goal()) if problem.goal else problem
        translation = translate(domain_text, problem_to_pddl(open_goal))
    task = read_sas(translation.sas)
    if translation.goal_unreachable or problem.goal.formula is None:
        task = _without_goal(task)  # a conjunction's literals are the lifted goal's own
    return task.prune_axioms(problem.goal.positive | problem.goal.negative)


set_grounder(ground_problem)  # the data model grounds through the loader, never imports it


def _without_goal(task: GroundTask) -> GroundTask:
    return GroundTask(task.actions, task.axioms, frozenset(), frozenset(), task.action_costs)


def read_pddl_file(path: Path) -> str:
    """A PDDL file's text, read by the checked reader (:func:`twostep.util.files.
    read_input_bytes`); a file that is no regular file of bounded size, or not UTF-8 text,
    is a :class:`PDDLError` naming it."""
    try:
        data = read_input_bytes(path)
    except NotAFileError as error:
        raise PDDLError(str(error).removeprefix(f"{path}: "), str(path)) from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise PDDLError(
            f"not a text file (byte {error.start} is not UTF-8): expected PDDL", str(path)
        ) from None


def load_problem(
    domain_path: str | Path,
    problem_path: str | Path,
    cache_dir: str | Path | None = None,
    limits: GroundingLimits | None = None,
) -> Problem:
    """Read a domain file and a problem file, grounded.

    ``cache_dir``: keep the parsed and grounded problem there, so that the next process
    reads it back in milliseconds instead of parsing and running the translator. An entry
    is keyed by both files' paths and contents and by the reader's own code and the
    translator's release (:func:`_parser_version`): a change to any of them parses again.
    Files that do not parse raise as without a cache (nothing is stored). ``limits``:
    what grounding may use (:class:`~twostep.pddl.translator.GroundingLimits`; None: the
    limits set for the process, :func:`~twostep.pddl.translator.grounding_limits`).
    """
    with grounding_limits(limits):
        return _load_problem(Path(domain_path), Path(problem_path), cache_dir)


def _load_problem(domain_path: Path, problem_path: Path, cache_dir: str | Path | None) -> Problem:
    for path in (domain_path, problem_path):
        bad = file_problem(path)  # a FIFO, a device, a directory, a loop, too large
        if bad is not None:
            raise PDDLError(bad.removeprefix(f"{path}: "), str(path))
        if not path.is_file():
            raise PDDLError("no such file", str(path))
    domain_text, problem_text = read_pddl_file(domain_path), read_pddl_file(problem_path)
    sources = (str(domain_path), str(problem_path))
    if cache_dir is None:
        problem = parse_problem(domain_text, problem_text, *sources)
        problem.grounded  # noqa: B018 -- a loaded task is a grounded one
        return problem
    key = hashlib.sha256(
        json.dumps([_parser_version(), *sources, domain_text, problem_text]).encode()
    ).hexdigest()
    entry = Path(cache_dir) / f"{key}.pickle"
    cached = _cached_problem(entry, key, sources)
    if cached is not None:
        return cached
    problem = parse_problem(domain_text, problem_text, *sources)
    problem.grounded  # noqa: B018 -- the entry holds the grounding too
    payload = pickle.dumps(problem, protocol=pickle.HIGHEST_PROTOCOL)
    header = f"{CACHE_MAGIC} {key} {hashlib.sha256(payload).hexdigest()}\n".encode()
    with contextlib.suppress(OSError):  # a read-only cache only costs the parse
        write_bytes_atomic(entry, header + payload)
    return problem


# A task-cache entry: one header line (this tag, the entry's key, the SHA-256 of the
# pickle after it), then the pickled Problem. The header is checked before unpickling.
CACHE_MAGIC = "twostep-task-cache/1"


def _cached_problem(entry: Path, key: str, sources: tuple[str, str]) -> Problem | None:
    """The problem cached in ``entry`` when the entry is this task's own (its header names
    ``key``, its pickle has the checksum the header gives, and the problem read back is of
    these two files); None when absent, or after one warning line when it is not (another
    task's entry copied over it, a cut or edited file): the caller parses again and
    replaces it. An entry without a header (older twostep) is parsed again silently."""
    try:
        data = entry.read_bytes()
    except OSError:
        return None
    head, _, payload = data.partition(b"\n")
    if not head.startswith(CACHE_MAGIC.encode() + b" "):
        return None
    fields = head.decode("ascii", "replace").split(" ")
    why = None
    if len(fields) != 3 or fields[1] != key:
        why = "is another task's entry"
    elif hashlib.sha256(payload).hexdigest() != fields[2]:
        why = "has changed since it was written (checksum)"
    else:
        try:
            cached = pickle.loads(payload)  # our own entry, checked above
        except Exception:
            cached = None
        if isinstance(cached, Problem) and (cached.domain.source, cached.source) == sources:
            return cached
        why = "does not hold this task"
    print(f"warning: task cache entry {entry} {why}: parsing the task again", file=sys.stderr)
    return None


@functools.cache
def _parser_version() -> str:
    """Digest of what turns PDDL into a :class:`Problem`: this package's code and the
    up-fast-downward release whose translator grounds it."""
    digest = hashlib.sha256()
    for module in sorted(Path(__file__).parent.glob("*.py")):
        digest.update(module.name.encode() + b"\0" + module.read_bytes())
    with contextlib.suppress(metadata.PackageNotFoundError):
        digest.update(metadata.version("up-fast-downward").encode())
    return digest.hexdigest()


def parse_goal(text: str, problem: Problem, source: str = "subgoal") -> Goal:
    """Parse a PDDL goal and check it against ``problem``.

    Accepts ``(:goal (and ...))``, ``(and ...)``, a single literal, or several literals in a
    row. Raises :class:`PDDLError` naming the first unknown predicate, wrong arity or
    unknown object. A goal with quantifiers or disjunctions is grounded by the task's
    static facts (:func:`~twostep.pddl.goals.ground_goal`).
    """
    exprs = read_sexp(text, source)
    if len(exprs) == 1 and isinstance(exprs[0], list) and exprs[0][:1] == [":goal"]:
        exprs = exprs[0][1:]
    if len(exprs) == 1 and isinstance(exprs[0], list) and exprs[0][:1] == ["and"]:
        exprs = exprs[0][1:]
    if not exprs:
        raise PDDLError("the goal is empty", source)
    if any(isinstance(expr, list) and conjunction_literals(expr) is None for expr in exprs):
        return ground_goal(exprs, problem, source)
    objects = problem.all_objects
    positive: set[Fact] = set()
    negative: set[Fact] = set()
    for expr in exprs:
        is_positive = True
        if isinstance(expr, list) and expr[:1] == ["not"] and len(expr) == 2:
            is_positive, expr = False, expr[1]
        if not isinstance(expr, list) or not expr or not all(isinstance(t, str) for t in expr):
            raise PDDLError(f"not a ground literal: {write_sexp(expr)}", source)
        pred, *args = [str(t) for t in expr]
        if pred not in problem.domain.predicates:
            raise PDDLError(f"unknown predicate '{pred}'", source)
        arity = len(problem.domain.predicates[pred])
        if len(args) != arity:
            raise PDDLError(f"'{pred}' takes {arity} argument(s), got {len(args)}", source)
        for arg in args:
            if arg not in objects:
                raise PDDLError(f"unknown object '{arg}' in {write_sexp(expr)}", source)
        (positive if is_positive else negative).add((pred, *args))
    if positive & negative:
        raise PDDLError("the goal asks for a fact and its negation", source)
    derived = problem.domain.derived_predicates
    for fact in sorted(f for f in positive | negative if f[0] in derived):
        if fact not in problem.grounded.axioms.derived:
            raise PDDLError(
                f"{fact_to_pddl(fact)} is a derived fact the task never evaluates (Fast "
                "Downward grounds only the derived facts its actions and goal use): name "
                "basic facts instead",
                source,
            )
    return Goal(frozenset(positive), frozenset(negative))
