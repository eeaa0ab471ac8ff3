"""One check's outcome, and how it is shown: a line of the doctor's report."""

from __future__ import annotations

import shlex
import sys
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path


class Status(StrEnum):
    """How a check came out. ``fail``: a needed part is missing (the doctor exits 1);
    ``warn``: an optional part is missing; ``skip``: nothing to check."""

    OK = "ok"
    WARN = "warn"
    FAIL = "fail"
    SKIP = "skip"


#: The mark a report line starts with: a failure stands out in capitals.
MARKS = {Status.OK: "ok", Status.WARN: "warn", Status.FAIL: "FAIL", Status.SKIP: "skip"}

#: Width of the name column of the report, in characters (the longest check's name).
NAME_WIDTH = 14


@dataclass(frozen=True)
class Check:
    """What one check found: its ``name``, ``status``, what was found (``detail``) and,
    for a problem, the shell command that fixes it (``fix``)."""

    name: str
    status: Status
    detail: str
    fix: str | None = None


def report_line(check: Check, name_width: int = NAME_WIDTH) -> str:
    """``check`` as one line: mark, name, what was found, and the fix for a problem."""
    line = f"{MARKS[check.status]:<4}  {check.name:<{name_width}}  {check.detail}"
    return f"{line}; fix: {check.fix}" if check.fix else line


def python_shown() -> str:
    """This interpreter as a user would type it: relative to the working directory when
    inside it (``.venv/bin/python``), else its absolute path."""
    return shown_path(Path(sys.executable))


def shown_path(path: Path) -> str:
    """``path`` as a user would type it: relative to the working directory when inside it,
    else absolute."""
    try:
        shown = str(path.relative_to(Path.cwd()))
    except ValueError:
        shown = str(path)
    return shlex.quote(shown)


def pip_command() -> str:
    """The pip of the environment llm-grop runs in."""
    return f"{python_shown()} -m pip"


def one_line(text: str) -> str:
    """``text`` with its whitespace runs (newlines included) folded to single spaces."""
    return " ".join(text.split())

