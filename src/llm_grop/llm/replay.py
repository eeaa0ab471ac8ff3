"""The ``replay`` backend: serves the responses of a record file
(:mod:`llm_grop.llm.record`) instead of calling a model.

Replayed records keep the recorded ``model``, ``latency_s``, token counts and seed;
only ``backend`` becomes ``"replay"``. So replaying a run twice gives identical
records, and a replayed run differs from the recorded one only in ``backend``.
"""

from __future__ import annotations

import copy
import hashlib
import json
from dataclasses import asdict, replace
from pathlib import Path

from llm_grop.errors import BadInput, ReplayMissing
from llm_grop.llm.base import BackendOptions, BaseLLM, SamplingParams
from llm_grop.llm.record import LLMCallRecord, load_records

#: Characters of the prompt quoted in a ReplayMissing message.
_PROMPT_PREVIEW = 60

class ReplayLLM(BaseLLM):
    """Serves the responses of a record file instead of calling a model.

    A call is looked up by ``(prompt, seed)``; sampling settings and grammar play no
    part. When a key was recorded several times its responses are served in recorded
    order and the last one repeats, counted within one run (:meth:`for_run`). ``model``
    names the recorded model(s), joined with ``+`` when the file mixes several.
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
        #: What the LLM cache keys this backend's answers by: the recorded file's content.
        self.cache_identity: str = "replay:" + hashlib.sha256(
            "\n".join(json.dumps(asdict(r), sort_keys=True) for r in self.records).encode()
        ).hexdigest()[:32]

    def for_run(self) -> ReplayLLM:
        """This recording with its order of repeated answers from the start: each run
        (a bench trial, a service job) is served as if it came first."""
        fresh = copy.copy(self)
        fresh._served = {}
        return fresh

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
