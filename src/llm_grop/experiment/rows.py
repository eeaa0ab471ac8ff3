"""A results directory's trial rows, ``trials.jsonl``: reading them and writing them.

One :class:`~llm_grop.contract.models.TrialRow` a line, appended and synced as each trial
ends, rewritten atomically. This module runs no pipeline (it imports records only), so
what reads results without running trials, such as the rating site, reads them here
(:func:`llm_grop.experiment.runner.read_rows` is this one too).
"""

from __future__ import annotations

import json
import logging
import os
import secrets
from pathlib import Path

from llm_grop.contract.models import TrialRow
from llm_grop.contract.serialize import read_doc
from llm_grop.errors import BadInput

log = logging.getLogger(__name__)

#: The file, in a results directory, that holds its trials' rows.
ROWS = "trials.jsonl"


def read_rows(out: Path) -> list[TrialRow]:
    """The finished trials' rows, each ``(method, task, trial)`` once (the first written,
    unless only a later one has an LLM answer); a last line cut off by a crash is
    dropped."""
    path = out / ROWS
    if not path.exists():
        return []
    rows = []
    lines = path.read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        try:
            data = json.loads(line)
        except ValueError:
            if i == len(lines) - 1:
                break
            raise BadInput(f"{path} line {i + 1}: not a JSON row") from None
        rows.append(read_doc(TrialRow, data, f"{path} line {i + 1}"))
    first: dict[tuple[str, int, int], TrialRow] = {}
    for row in rows:
        kept = first.get(row_key(row))
        if kept is None or kept.status == "llm-failed" and row.status != "llm-failed":
            first[row_key(row)] = row
    if len(first) < len(rows):
        # Two runs wrote here before runs took the directory's lock; the first row of a
        # trial is kept, and the next resume rewrites the file without the others.
        log.warning("%s: %d duplicate rows ignored (the first of each trial is kept)", path,
                    len(rows) - len(first))
    return list(first.values())


def row_key(row: TrialRow) -> tuple[str, int, int]:
    """Which trial ``row`` is: ``(method, task, trial)``."""
    return (row.method, row.task, row.trial)


def table_order(row: TrialRow) -> tuple[int, int, str]:
    """The sort key of the results file: ``(task, trial, method)``."""
    return (row.task, row.trial, row.method)


def _line(row: TrialRow) -> str:
    return json.dumps(row.to_json(), separators=(",", ":")) + "\n"


def sort_rows_file(out: Path) -> None:
    """Rewrite the results file in ``(task, trial, method)`` order, its lines as they are
    (each was checked when written, so it is only parsed for its key, not validated)."""
    def key(line: str) -> tuple[int, int, str]:
        row = json.loads(line)
        return (row["task"], row["trial"], row["method"])

    lines = (out / ROWS).read_text(encoding="utf-8").splitlines(keepends=True)
    _write_lines(out, sorted((line for line in lines if line.strip()), key=key))


def append_row(path: Path, row: TrialRow) -> None:
    """Append ``row`` to the results file ``path`` as one line, synced to disk."""
    with path.open("a", encoding="utf-8") as f:
        f.write(_line(row))
        f.flush()
        os.fsync(f.fileno())


def rewrite_rows(out: Path, rows: list[TrialRow]) -> None:
    """Write ``rows`` as the results file, atomically."""
    _write_lines(out, [_line(row) for row in rows])


def _write_lines(out: Path, lines: list[str]) -> None:
    """Write ``lines`` (each ending in a newline) as the results file, atomically."""
    tmp = out / f".{ROWS}.{os.getpid()}-{secrets.token_hex(4)}.tmp"
    with tmp.open("w", encoding="utf-8") as f:
        f.writelines(lines)
        f.flush()
        os.fsync(f.fileno())
    tmp.replace(out / ROWS)
