"""The registry of LLM backends (see :mod:`llm_grop.plugins`): entry point group
``llm_grop.llm_backends``; an entry is a factory ``(BackendOptions) -> LLM``."""

from __future__ import annotations

from collections.abc import Callable

from llm_grop.llm.base import LLM, BackendOptions
from llm_grop.plugins import Registry

Factory = Callable[[BackendOptions], LLM]


BACKENDS: Registry[Factory] = Registry(
    group="llm_grop.llm_backends", kind="backend", flag="--llm", module=__name__,
    builtins={"embedded": "llm_grop.llm.embedded:EmbeddedLLM",
              "openai": "llm_grop.llm.openai_backend:OpenAILLM",
              "replay": "llm_grop.llm.replay:ReplayLLM"},
    factory="(BackendOptions) -> LLM", protocol=LLM,
    product=("backend", "model", "supports_schema", "cache_identity", "complete", "close"))


def register_backend(name: str, factory: Factory) -> None:
    """Add a backend, selectable as ``--llm NAME``, in this process (and the bench's
    workers)."""
    BACKENDS.register(name, factory)


def available_backends() -> list[str]:
    """Names of every available backend."""
    return BACKENDS.names()


def create_llm(name: str, options: BackendOptions | None = None) -> LLM:
    """Build the backend called ``name``; its heavy imports happen only here."""
    llm: LLM = BACKENDS.create(name, options or BackendOptions())
    return llm
