"""The LLM protocol, its sampling and construction options, and the call log."""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, ClassVar, Protocol, runtime_checkable

from llm_grop.llm.cache import CallKey, LLMCache, backend_identity
from llm_grop.llm.record import LLMCallRecord, append_record
from llm_grop.settings import DEFAULTS
from llm_grop.settings.declared import NoOptions

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SamplingParams:
    """Decoding settings. Defaults are the paper's Table II hyperparameters.

    ``seed`` makes a call repeatable; re-prompting resamples by changing it.
    """

    temperature: float = DEFAULTS.temperature
    top_p: float = DEFAULTS.top_p
    max_tokens: int = DEFAULTS.max_tokens
    frequency_penalty: float = DEFAULTS.frequency_penalty
    presence_penalty: float = DEFAULTS.presence_penalty
    seed: int | None = None

    def with_seed(self, seed: int | None) -> SamplingParams:
        """A copy with another seed."""
        return replace(self, seed=seed)


@dataclass(frozen=True)
class BackendOptions:
    """How to build a backend.

    ``model``: model name (openai) or GGUF path (embedded); ``None`` for the default.
    ``base_url``/``api_key``: for openai (default: ``OPENAI_BASE_URL``/``OPENAI_API_KEY``).
    ``timeout_s``: seconds one call may take, retries and their waits included.
    ``max_retries``: retries with exponential backoff on transient errors (connection, 429,
    5xx). ``max_answer_bytes``: the largest answer accepted, bytes.
    ``replay_path``: the JSONL file the replay backend reads.
    ``n_threads``: CPU threads for the embedded model (``None``: all cores).
    ``own``: the backend's own options, an instance of the ``Options`` it declares
    (:class:`BaseLLM`), checked by :func:`~llm_grop.llm.registry.create_llm`; ``None``:
    its defaults.
    """

    model: str | None = None
    base_url: str | None = None
    api_key: str | None = None
    timeout_s: float = DEFAULTS.timeout_s
    max_retries: int = DEFAULTS.retries
    max_answer_bytes: int = DEFAULTS.max_answer_bytes
    replay_path: Path | None = None
    n_threads: int | None = None
    own: Any = None


@runtime_checkable
class LLM(Protocol):
    """A text-completion model.

    ``complete`` sends ``prompt`` as one user message and returns the call's record.
    ``grammar`` is an optional GBNF grammar that constrains the output; backends
    that cannot enforce one ignore it.

    Besides answering, a backend declares what it can do (a plugin inherits the
    defaults from :class:`BaseLLM`); callers read the declaration and never probe:

    - ``supports_schema``: it can constrain its output to a JSON Schema; :class:`CallLog`
      then passes the schema as the keyword ``schema`` (a JSON Schema object). The prompt
      still asks for a format that reads without it, for servers that turn structured
      output down.
    - ``cache_identity``: what its answers depend on (a model file and llama.cpp's
      version, an endpoint and model, a recording's digest), for the LLM cache's key;
      ``None``: its answers are never cached.
    - :meth:`close` releases what it holds (a model, connections).
    """

    backend: str
    model: str
    supports_schema: bool
    cache_identity: str | None

    def complete(self, prompt: str, params: SamplingParams, grammar: str | None = None
                 ) -> LLMCallRecord: ...

    def close(self) -> None: ...


class BaseLLM:
    """The declarations of :class:`LLM` with the defaults a plugin backend inherits: no
    JSON Schema, never cached, nothing to release, no options of its own.

    A backend class registered as the factory declares its own options as ``Options``, a
    frozen dataclass (the way simonw/llm's models declare theirs): users set them with
    ``--llm-option KEY=VALUE`` (``llm.options`` in a sweep file), the registry checks them
    against it and hands the instance over as :attr:`BackendOptions.own`.
    """

    Options: ClassVar[type] = NoOptions
    supports_schema: bool = False
    cache_identity: str | None = None

    def for_run(self) -> BaseLLM:
        """The backend for one run's call log: itself; a backend that keeps state from
        call to call of a run (the replay's order of repeated answers) returns a copy with
        that state fresh, so that no run's answers depend on the runs before it."""
        return self

    def own_options(self, options: BackendOptions) -> Any:
        """The backend's own options in ``options`` (its declared defaults when none)."""
        return options.own if options.own is not None else self.Options()

    def close(self) -> None:
        """Release what the backend holds (nothing, by default)."""
        return None


@dataclass
class CallLog:
    """Wraps an :class:`LLM`, keeping every call and appending it to a record file.

    The record file is JSONL (one call a line, flushed at once, so an interrupted
    run loses no call); the replay backend reads it back. With a ``cache``, a seeded call
    asked before (by any process on the machine) is answered from it, its record marked
    ``cached``.
    """

    llm: LLM
    record_path: Path | None = None
    calls: list[LLMCallRecord] = field(default_factory=list)
    cache: LLMCache | None = None
    #: Wall-clock seconds spent in :meth:`complete` so far (recording included). Unlike
    #: the records' ``latency_s``, which a replay copies from the recording, this is the
    #: time this process really waited.
    wall_s: float = 0.0
    #: How ``--llm auto`` chose this backend, in one line (``None``: it was named).
    chosen_by: str | None = None

    @property
    def backend(self) -> str:
        return self.llm.backend

    @property
    def model(self) -> str:
        return self.llm.model

    def complete(self, prompt: str, params: SamplingParams, grammar: str | None = None,
                 schema: Mapping[str, Any] | None = None) -> LLMCallRecord:
        """The backend's answer to ``prompt``, kept and recorded; ``schema`` (a JSON Schema
        for the answer) reaches only backends that accept one."""
        t0 = time.perf_counter()
        if not self.llm.supports_schema:
            schema = None
        # An unseeded call is asked to differ from the last, so it is never cached.
        identity = backend_identity(self.llm) \
            if self.cache is not None and params.seed is not None else None
        key = None if identity is None else CallKey(self.llm.backend, identity, prompt,
                                                     asdict(params), grammar, schema)
        try:
            record = self.cache.get(key) if self.cache and key else None
            if record is None:
                record = self._ask(prompt, params, grammar, schema)
                if self.cache and key:
                    self.cache.put(key, record)
            self.calls.append(record)
            log.debug("%s call, seed %s: %.2f s, %s completion tokens", record.backend,
                      record.seed, record.latency_s, record.completion_tokens)
            if self.record_path is not None:
                append_record(self.record_path, record)
        finally:
            self.wall_s += time.perf_counter() - t0
        return record

    @property
    def cache_hits(self) -> int:
        """How many of :attr:`calls` the cache answered."""
        return sum(c.cached for c in self.calls)

    def _ask(self, prompt: str, params: SamplingParams, grammar: str | None,
             schema: Mapping[str, Any] | None) -> LLMCallRecord:
        if schema is not None:
            return self.llm.complete(prompt, params, grammar,
                                     schema=schema)  # type: ignore[call-arg]
        return self.llm.complete(prompt, params, grammar)
