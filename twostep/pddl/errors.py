"""The one error type of PDDL reading: what is wrong, in which file, on which line."""

from __future__ import annotations


class PDDLError(Exception):
    """A PDDL file or string that cannot be used, with where and what."""

    def __init__(self, message: str, source: str | None = None, line: int | None = None):
        self.message = message
        self.source = source
        self.line = line
        where = source or "<pddl>"
        if line is not None:
            where = f"{where}:{line}"
        super().__init__(f"{where}: {message}")
