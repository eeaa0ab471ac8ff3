"""Records of LLM calls, kept with an arrangement (no LLM code here)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class LLMCallRecord:
    """One LLM call: the prompt, the response, latency in seconds and token counts."""

    backend: str
    model: str
    prompt: str
    response: str
    latency_s: float
    prompt_tokens: int | None = None
    completion_tokens: int | None = None
    seed: int | None = None


@dataclass(frozen=True)
class LLMSummary:
    """The ``llm`` section of an arrangement: which model, how many calls, and each call."""

    backend: str
    model: str
    calls: tuple[LLMCallRecord, ...] = ()
