"""What an arrangement keeps of the LLM calls behind it (no LLM code here).

The LLM layer owns its call record (:class:`llm_grop.llm.record.LLMCallRecord`); the world
only describes what it reads of one, as a protocol, so it imports nothing from that layer.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol


class CallRecord(Protocol):
    """One LLM call as an arrangement keeps it: prompt, response, latency in seconds,
    token counts, the call's seed, and whether the LLM cache answered it."""

    @property
    def prompt(self) -> str: ...

    @property
    def response(self) -> str: ...

    @property
    def latency_s(self) -> float: ...

    @property
    def prompt_tokens(self) -> int | None: ...

    @property
    def completion_tokens(self) -> int | None: ...

    @property
    def seed(self) -> int | None: ...

    @property
    def cached(self) -> bool: ...


@dataclass(frozen=True)
class LLMSummary:
    """The ``llm`` section of an arrangement: which model, how many calls, and each call."""

    backend: str
    model: str
    calls: tuple[CallRecord, ...] = ()
    #: How ``--llm auto`` chose the model, in one line (``None``: it was named).
    chosen_by: str | None = None
