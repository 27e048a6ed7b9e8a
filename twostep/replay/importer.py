"""Logs into a replay bundle: ``twostep-data import-answers`` (:func:`import_logs`).

Each log file is one run per run label its ``TASK:`` lines name (blocks that crashed
before that line belong to the file's only label). All files are read and checked before
anything is written; the bundle is then written whole (:meth:`Bundle.save`), so a
malformed or truncated log leaves no half-written bundle behind.
"""

from __future__ import annotations

import hashlib
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from twostep.replay.bundle import (
    BUNDLE_FILE,
    Bundle,
    BundleError,
    Entry,
    Run,
    load_bundle,
    task_name,
)
from twostep.replay.official import FORMAT, LogFormatError, ParsedLog, parse_log
from twostep.util.files import NotTextError, read_input_bytes, read_text_file

FORMATS = (FORMAT,)


class AnswerImportError(ValueError):
    """The logs cannot be imported (the message names the file, and the line if any)."""


@dataclass
class ImportReport:
    """What an import did: the bundle, the runs it added, the blocks without answers."""

    bundle: Bundle
    added: list[Run] = field(default_factory=list)
    without_answers: dict[str, int] = field(default_factory=dict)  # file -> blocks

    def lines(self) -> list[str]:
        out = []
        for run in self.added:
            entries = [e for e in self.bundle.entries if e.run == run.id]
            per = Counter((e.domain, e.agents) for e in entries)
            cells = ", ".join(f"{d} N={n}: {c}" for (d, n), c in sorted(per.items()))
            label = f" run {run.label}" if run.label else ""
            out.append(f"{run.file}{label} ({run.model}): {len(entries)} task(s): {cells}")
        for name, count in self.without_answers.items():
            if count:
                out.append(f"{name}: {count} block(s) without answers (the run failed before them)")
        return out


def _read(path: Path) -> str:
    if not path.is_file():
        raise AnswerImportError(f"{path}: not a file")
    try:
        return read_text_file(path)
    except NotTextError as error:
        raise AnswerImportError(str(error)) from None
    except OSError as error:
        raise AnswerImportError(f"{path}: {error.strerror or error}") from None


def _runs_of(parsed: ParsedLog, model: str, digest: str, taken: set[str]) -> list[Run]:
    labels: list[str | None] = list(parsed.run_labels) or [None]
    stem = parsed.path.stem
    runs = []
    for label in labels:
        base = stem if len(labels) <= 1 else f"{stem}#{label}"
        run_id, k = base, 2
        while run_id in taken:
            run_id, k = f"{base}.{k}", k + 1
        taken.add(run_id)
        runs.append(
            Run(
                id=run_id,
                model=model,
                file=parsed.path.name,
                path=str(parsed.path),
                sha256=digest,
                label=label,
                format=FORMAT,
            )
        )
    return runs


def import_logs(
    paths: Sequence[Path],
    model: str,
    out: Path,
    *,
    log_format: str = FORMAT,
    tasks: Path | None = None,
    append: bool = False,
    allow_truncated: bool = False,
) -> ImportReport:
    """Read ``paths`` (logs of ``log_format``, answers of ``model``) into the bundle in
    ``out``; with ``append``, add them to the bundle already there. ``tasks``: the folder
    of the task files the logs refer to (``<tasks>/<domain>/pNN.pddl``), whose digests the
    bundle keeps so that a replay on other files is refused. ``allow_truncated``: a log
    that ends inside a block is imported without that block (else an error)."""
    if log_format not in FORMATS:
        raise AnswerImportError(f"unknown log format '{log_format}' (known: {', '.join(FORMATS)})")
    if not model.strip():
        raise AnswerImportError("--model: name the model that gave the answers (e.g. gpt-4o)")
    existing = Path(out) / BUNDLE_FILE
    if existing.exists() and not append:
        raise AnswerImportError(
            f"{existing} exists: add to it with --append, or choose another --out"
        )
    try:
        bundle = load_bundle(out) if append and existing.exists() else Bundle()
    except BundleError as error:
        raise AnswerImportError(str(error)) from None
    bundle = Bundle(runs=list(bundle.runs), entries=list(bundle.entries), tasks=dict(bundle.tasks))
    report = ImportReport(bundle)
    taken = {r.id for r in bundle.runs}
    known = {(r.sha256, r.model): r for r in bundle.runs}
    for path in paths:
        path = Path(path)
        text = _read(path)
        digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
        if (digest, model) in known:
            raise AnswerImportError(
                f"{path}: already in the bundle as run {known[(digest, model)].id} ({model})"
            )
        try:
            parsed = parse_log(path, text, allow_truncated)
        except LogFormatError as error:
            raise AnswerImportError(str(error)) from None
        report.without_answers[path.name] = len(parsed.without_answers)
        if not parsed.entries:
            raise AnswerImportError(
                f"{path}: no answers in {parsed.blocks} block(s) (is it a {log_format} log?)"
            )
        runs = _runs_of(parsed, model, digest, taken)
        by_label = {r.label: r for r in runs}
        only = runs[0] if len(runs) == 1 else None
        for entry in parsed.entries:
            run = by_label.get(entry.run_label) or only
            if run is None:  # a crashed block in a file of several runs: no run to give it
                raise AnswerImportError(
                    f"{path}:{entry.line}: the block has no 'TASK: ...' line and the file "
                    f"holds several runs ({', '.join(r.label or '' for r in runs)})"
                )
            bundle.entries.append(
                Entry(
                    run=run.id,
                    domain=entry.domain,
                    task=entry.task,
                    agents=entry.agents,
                    line=entry.line,
                    answers=entry.answers,
                    official=entry.official,
                    translations=entry.translations,
                )
            )
        bundle.runs.extend(runs)
        report.added.extend(runs)
        for run in runs:
            known[(digest, model)] = run
    if tasks is not None:
        _record_tasks(bundle, Path(tasks))
    bundle = Bundle(runs=bundle.runs, entries=bundle.entries, tasks=bundle.tasks)
    bundle.save(Path(out))
    report.bundle = bundle
    return report


def _record_tasks(bundle: Bundle, folder: Path) -> None:
    if not folder.is_dir():
        raise AnswerImportError(f"--tasks {folder}: not a folder")
    for domain, task in sorted({(e.domain, e.task) for e in bundle.entries}):
        path = folder / domain / f"p{task:02d}.pddl"
        if not path.is_file():
            raise AnswerImportError(
                f"--tasks {folder}: no {domain}/p{task:02d}.pddl (the logs answer that task)"
            )
        try:
            data = read_input_bytes(path)
        except (OSError, NotTextError) as error:
            raise AnswerImportError(f"--tasks {folder}: {error}") from None
        bundle.tasks[task_name(domain, task)] = hashlib.sha256(data).hexdigest()
