"""The ``replay`` backend and the record file it reads.

A record file is JSONL: one recorded call a line, an object with the keys
``backend, model, prompt, response, latency_s, prompt_tokens, completion_tokens,
seed`` (UTF-8, non-ASCII kept as is). :class:`~llm_grop.llm.base.CallLog` writes it
through :func:`append_record`; :class:`ReplayLLM` serves it back.

Replayed records keep the recorded ``model``, ``latency_s``, token counts and seed;
only ``backend`` becomes ``"replay"``. So replaying a run twice gives identical
records, and a replayed run differs from the recorded one only in ``backend``.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, replace
from pathlib import Path

from llm_grop.errors import BadInput, LLMError, ReplayMissing
from llm_grop.llm.base import BackendOptions, SamplingParams
from llm_grop.world.llmlog import LLMCallRecord

#: Characters of the prompt quoted in a ReplayMissing message.
_PROMPT_PREVIEW = 60

_REQUIRED_STR = ("backend", "model", "prompt", "response")
_OPTIONAL_INT = ("prompt_tokens", "completion_tokens", "seed")


def append_record(path: Path, record: LLMCallRecord) -> None:
    """Append ``record`` to the JSONL file ``path`` as one line, flushed and fsynced.

    One ``write`` per line on a file opened for appending keeps lines whole even when
    the process dies right after; the parent directory is created if needed.
    """
    line = json.dumps(asdict(record), ensure_ascii=False) + "\n"
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
    for number, line in enumerate(text.splitlines(), start=1):
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


class ReplayLLM:
    """Serves the responses of a record file instead of calling a model.

    A call is looked up by ``(prompt, seed)``; sampling settings and grammar play no
    part. When a key was recorded several times its responses are served in recorded
    order and the last one repeats. ``model`` names the recorded model(s), joined
    with ``+`` when the file mixes several.
    """

    backend: str = "replay"

    def __init__(self, options: BackendOptions) -> None:
        if options.replay_path is None:
            raise BadInput("replay backend: no replay file given (the JSONL file a recorded "
                           "run wrote)")
        self.path: Path = Path(options.replay_path)
        self.records: tuple[LLMCallRecord, ...] = tuple(load_records(self.path))
        self._by_key: dict[tuple[str, int | None], list[LLMCallRecord]] = {}
        for record in self.records:
            self._by_key.setdefault((record.prompt, record.seed), []).append(record)
        self._served: dict[tuple[str, int | None], int] = {}
        models = dict.fromkeys(record.model for record in self.records)
        self.model: str = "+".join(models) or "none"

    def complete(self, prompt: str, params: SamplingParams, grammar: str | None = None
                 ) -> LLMCallRecord:
        """The recorded answer to ``prompt`` at ``params.seed``, as a ``replay`` record."""
        key = (prompt, params.seed)
        recorded = self._by_key.get(key)
        if not recorded:
            preview = " ".join(prompt.split())
            if len(preview) > _PROMPT_PREVIEW:
                preview = preview[:_PROMPT_PREVIEW] + "…"
            raise ReplayMissing(f"{self.path.name}: no recorded response for prompt {preview!r} "
                                f"with seed {params.seed} ({len(self.records)} calls recorded)")
        index = self._served.get(key, 0)
        self._served[key] = index + 1
        return replace(recorded[min(index, len(recorded) - 1)], backend=self.backend)
