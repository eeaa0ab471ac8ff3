"""The registry of LLM backends (see :mod:`llm_grop.plugins`): entry point group
``llm_grop.llm_backends``; an entry is a factory ``(BackendOptions) -> LLM``: a
:class:`~llm_grop.llm.base.BaseLLM` subclass, which declares its own ``Options``, or a
function, which declares none."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

from llm_grop.llm.base import LLM, BackendOptions, BaseLLM
from llm_grop.plugins import Registry
from llm_grop.settings.declared import NoOptions, declared_options

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


def backend_options_class(name: str) -> type:
    """The ``Options`` dataclass the backend called ``name`` declares (a factory that is
    no :class:`BaseLLM` subclass declares none)."""
    factory = BACKENDS.get(BACKENDS.key(name))
    if isinstance(factory, type) and issubclass(factory, BaseLLM):
        return factory.Options
    return NoOptions


def create_llm(name: str, options: BackendOptions | None = None,
               own: Mapping[str, Any] | None = None) -> LLM:
    """Build the backend called ``name`` with ``options`` and ``own``, its own options by
    name (checked against the ``Options`` it declares: :class:`BadInput` naming
    ``backend_options.KEY``); its heavy imports happen only here."""
    options = options or BackendOptions()
    if own or options.own is None:
        made = declared_options(backend_options_class(name), own or {},
                                owner=f"LLM backend {BACKENDS.key(name)!r}",
                                param="backend_options")
        options = replace(options, own=made)
    llm: LLM = BACKENDS.create(name, options)
    return llm
