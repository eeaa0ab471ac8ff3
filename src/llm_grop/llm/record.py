"""The LLM layer's record of one call, and the JSONL record file it is kept in.

A record file is JSONL: one recorded call a line, an object with the keys
``backend, model, prompt, response, latency_s, prompt_tokens, completion_tokens,
seed``, and ``cached: true`` when the answer came from the LLM cache
(:mod:`llm_grop.llm.cache`) (UTF-8, non-ASCII kept as is).
:class:`~llm_grop.llm.base.CallLog` appends to it through :func:`append_record`; the
replay backend reads it with :func:`load_records`.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path

from llm_grop.errors import BadInput, LLMError


@dataclass(frozen=True)
class LLMCallRecord:
    """One LLM call: the prompt, the response, latency in seconds, token counts and the
    seed it was made with. ``cached`` is true when the answer came from the LLM cache, not
    the model (``latency_s`` then is the original call's)."""

    backend: str
    model: str
    prompt: str
    response: str
    latency_s: float
    prompt_tokens: int | None = None
    completion_tokens: int | None = None
    seed: int | None = None
    cached: bool = False


_REQUIRED_STR = ("backend", "model", "prompt", "response")
_OPTIONAL_INT = ("prompt_tokens", "completion_tokens", "seed")


def append_record(path: Path, record: LLMCallRecord) -> None:
    """Append ``record`` to the JSONL file ``path`` as one line, flushed and fsynced.

    One ``write`` per line on a file opened for appending keeps lines whole even when
    the process dies right after; the parent directory is created if needed.
    """
    data = asdict(record)
    if not data["cached"]:
        del data["cached"]  # lines stay as they were before the cache existed
    line = json.dumps(data, ensure_ascii=False) + "\n"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("a", encoding="utf-8") as handle:
            handle.write(line)
            handle.flush()
            os.fsync(handle.fileno())
    except OSError as exc:
        raise BadInput(f"{path}: cannot append the LLM call record: {exc.strerror or exc}"
                       ) from None


def load_records(path: Path) -> list[LLMCallRecord]:
    """Every record in the JSONL file ``path``, in file order; blank lines are skipped.

    Raises :class:`LLMError` naming the file (and the line, for a malformed record).
    """
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise LLMError(f"{path}: replay file not found") from None
    except UnicodeDecodeError as exc:
        line = _line_of_byte(path, exc.start)
        raise LLMError(f"{path}:{line}: replay file is not UTF-8") from None
    except OSError as exc:
        raise LLMError(f"{path}: cannot read replay file: {exc.strerror or exc}") from None
    records = []
    # Records are separated by "\n" alone: str.splitlines() would also split inside a
    # response at "\x85" or "\u2028", which JSON keeps as they are (ensure_ascii=False).
    for number, line in enumerate(text.split("\n"), start=1):
        if line.strip():
            records.append(_parse_line(path, number, line))
    return records


def _line_of_byte(path: Path, offset: int) -> int:
    """The 1-based line holding byte ``offset`` of ``path``."""
    with path.open("rb") as handle:
        return handle.read(offset).count(b"\n") + 1


def _parse_line(path: Path, number: int, line: str) -> LLMCallRecord:
    where = f"{path}:{number}"
    try:
        data = json.loads(line)
    except json.JSONDecodeError as exc:
        raise LLMError(f"{where}: malformed replay record: {exc.msg} at column {exc.colno}"
                       ) from None
    return record_from_dict(data, where)


def record_from_dict(data: object, where: str) -> LLMCallRecord:
    """A call record from its JSON object, every field checked; :class:`LLMError` naming
    ``where`` and the field otherwise."""
    if not isinstance(data, dict):
        raise LLMError(f"{where}: malformed replay record: expected a JSON object")
    for key in _REQUIRED_STR:
        if not isinstance(data.get(key), str):
            raise LLMError(f"{where}: replay record needs a string {key!r}")
    latency = data.get("latency_s")
    if isinstance(latency, bool) or not isinstance(latency, int | float) or not (
            math.isfinite(latency) and latency >= 0):
        raise LLMError(f"{where}: replay record needs a non-negative number 'latency_s'")
    for key in _OPTIONAL_INT:
        value = data.get(key)
        if value is not None and (isinstance(value, bool) or not isinstance(value, int)):
            raise LLMError(f"{where}: replay record field {key!r} must be an integer or null")
    return LLMCallRecord(
        backend=data["backend"],
        model=data["model"],
        prompt=data["prompt"],
        response=data["response"],
        latency_s=float(latency),
        prompt_tokens=data.get("prompt_tokens"),
        completion_tokens=data.get("completion_tokens"),
        seed=data.get("seed"),
    )
