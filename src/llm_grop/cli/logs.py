"""``-v``/``--verbose``: llm-grop's log records on stderr, one line each."""

from __future__ import annotations

import logging
import sys
from typing import Any

import click

#: Log level by the number of -v flags.
_LEVELS = (logging.WARNING, logging.INFO, logging.DEBUG)


def _verbosity(ctx: click.Context, _param: click.Parameter, count: int) -> None:
    # Given before the command (`llm-grop -v run`) or after it (`llm-grop run -v`): the
    # larger count wins.
    root = ctx.find_root()
    count = max(count, root.meta.get("llm_grop.verbose", 0))
    root.meta["llm_grop.verbose"] = count
    configure_logging(_LEVELS[min(count, len(_LEVELS) - 1)])


VERBOSE = click.option(
    "-v", "--verbose", count=True, expose_value=False, is_eager=True, callback=_verbosity,
    help="Log what happens to stderr: -v for each step, -vv for every detail.")


def configure_logging(level: int) -> None:
    """Send llm-grop's log records of ``level`` and above to stderr, one line each."""
    logger = logging.getLogger("llm_grop")
    logger.setLevel(level)
    if not logger.handlers:
        handler = _StderrHandler()
        handler.setFormatter(_Formatter())
        logger.addHandler(handler)


class _StderrHandler(logging.StreamHandler):  # type: ignore[type-arg]
    """Writes to whatever ``sys.stderr`` is at the time (tests and rich replace it)."""

    @property  # type: ignore[override]
    def stream(self) -> Any:
        return sys.stderr

    @stream.setter
    def stream(self, _value: Any) -> None:
        pass


class _Formatter(logging.Formatter):
    """``llm-grop: warning: ...``; with -v, the logger's name too."""

    def format(self, record: logging.LogRecord) -> str:
        where = "" if record.levelno >= logging.WARNING else f"{record.name}: "
        return f"llm-grop: {record.levelname.lower()}: {where}{record.getMessage()}"
