"""The LLM layer's record of one call, and the JSONL record file it is kept in.

A record file is JSONL: one recorded call a line, an object with the keys
``backend, model, prompt, response, latency_s, prompt_tokens, completion_tokens,
seed``, and ``cached: true`` when the answer came from the LLM cache
(:mod:`llm_grop.llm.cache`) (UTF-8, non-ASCII kept as is).
:class:`~llm_grop.llm.base.CallLog` appends to it through :func:`append_record`; the
replay backend reads it with :func:`load_records`. Both, and the LLM cache, open only
regular files (:func:`open_regular`).
"""

from __future__ import annotations

import errno
import json
import math
import os
import stat
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


class NotRegularFile(OSError):
    """A path that names something other than a regular file: a FIFO, a device, a socket,
    a directory, or a symbolic link where none is followed."""

    def __init__(self, kind: str) -> None:
        super().__init__(errno.EINVAL, f"not a regular file ({kind})")


_KINDS = ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISDIR, "a directory"), (stat.S_ISLNK, "a symbolic link"))


def _check_regular(mode: int) -> None:
    if not stat.S_ISREG(mode):
        raise NotRegularFile(next((kind for test, kind in _KINDS if test(mode)),
                                  "a special file"))


def check_regular(path: Path, *, follow: bool = True) -> None:
    """:class:`NotRegularFile` unless ``path`` names a regular file (symbolic links followed
    unless ``follow`` is false), :class:`FileNotFoundError` if it names nothing; the file is
    not opened."""
    _check_regular(os.stat(path, follow_symlinks=follow).st_mode)


def open_regular(path: Path, flags: int, *, follow: bool = True) -> int:
    """A descriptor of the regular file ``path`` opened with ``flags`` (``os.O_CREAT``
    among them creates it); :class:`NotRegularFile` for anything else, found before it is
    opened and again on the descriptor. Symbolic links are followed unless ``follow`` is
    false. Never blocks: a FIFO waits for a peer when opened, a device may never end."""
    try:
        check_regular(path, follow=follow)
    except FileNotFoundError:
        if not flags & os.O_CREAT:
            raise
    # O_NONBLOCK: should a FIFO take the path's place meanwhile, opening it returns at
    # once and the descriptor's own check refuses it.
    flags |= os.O_NONBLOCK | os.O_CLOEXEC | (0 if follow else os.O_NOFOLLOW)
    try:
        fd = os.open(path, flags, 0o666)
    except OSError as exc:
        if exc.errno == errno.ELOOP and not follow:
            raise NotRegularFile("a symbolic link") from None
        if exc.errno == errno.ENXIO:  # a FIFO opened for writing with no reader
            raise NotRegularFile("a FIFO") from None
        raise
    try:
        _check_regular(os.fstat(fd).st_mode)
    except NotRegularFile:
        os.close(fd)
        raise
    return fd


_REQUIRED_STR = ("backend", "model", "prompt", "response")
_OPTIONAL_INT = ("prompt_tokens", "completion_tokens", "seed")


def append_record(path: Path, record: LLMCallRecord) -> None:
    """Append ``record`` to the JSONL file ``path`` as one line, flushed and fsynced.

    One ``write`` per line on a file opened for appending keeps lines whole even when
    the process dies right after; the parent directory is created if needed. A path that
    is no regular file (:func:`open_regular`) is :class:`BadInput`.
    """
    data = asdict(record)
    if not data["cached"]:
        del data["cached"]  # lines stay as they were before the cache existed
    line = json.dumps(data, ensure_ascii=False) + "\n"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = open_regular(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
        with open(fd, "a", encoding="utf-8") as handle:
            handle.write(line)
            handle.flush()
            os.fsync(handle.fileno())
    except OSError as exc:
        raise BadInput(f"{path}: cannot append the LLM call record: {exc.strerror or exc}"
                       ) from None


def load_records(path: Path) -> list[LLMCallRecord]:
    """Every record in the JSONL file ``path``, in file order; blank lines are skipped.

    Raises :class:`LLMError` naming the file (and the line, for a malformed record), for
    a path that is no regular file too (:func:`open_regular`).
    """
    try:
        with open(open_regular(path, os.O_RDONLY), "rb") as handle:
            text = handle.read().decode("utf-8")
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
