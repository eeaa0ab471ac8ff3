"""Every registered backend keeps the LLM contract on a tiny prompt."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from llm_grop.llm.base import LLM, BackendOptions, CallLog, SamplingParams
from llm_grop.llm.registry import available_backends, create_llm

if TYPE_CHECKING:
    from conftest import ChatServer

PROMPT = "List two things on a dinner table."
PARAMS = SamplingParams(temperature=0.7, max_tokens=8, seed=42)


def _openai(server: ChatServer, tmp_path: Path) -> LLM:
    return create_llm("openai", BackendOptions(base_url=server.url, model="tiny"))


def _replay(server: ChatServer, tmp_path: Path) -> LLM:
    path = tmp_path / "recorded.jsonl"
    CallLog(_openai(server, tmp_path), path).complete(PROMPT, PARAMS)
    return create_llm("replay", BackendOptions(replay_path=path))


def _embedded(server: ChatServer, tmp_path: Path) -> LLM:
    return create_llm("embedded", BackendOptions())


BUILDERS: dict[str, Callable[[ChatServer, Path], LLM]] = {
    "openai": _openai,
    "replay": _replay,
    "embedded": _embedded,
}


@pytest.fixture(params=[pytest.param(name, marks=[pytest.mark.embedded] if name == "embedded"
                                     else []) for name in available_backends()])
def backend(request: pytest.FixtureRequest, chat_server: ChatServer, tmp_path: Path
            ) -> Iterator[LLM]:
    name = request.param
    if name not in BUILDERS:
        pytest.fail(f"no contract test builder for backend {name!r}")
    llm = BUILDERS[name](chat_server, tmp_path)
    yield llm
    close = getattr(llm, "close", None)
    if close is not None:
        close()


def test_record_is_well_formed_and_repeatable(backend: LLM) -> None:
    assert isinstance(backend, LLM)
    first = backend.complete(PROMPT, PARAMS)
    second = backend.complete(PROMPT, PARAMS)
    for record in (first, second):
        assert record.backend == backend.backend
        assert record.model == backend.model
        assert record.prompt == PROMPT
        assert record.seed == 42
        assert isinstance(record.response, str) and record.response.strip()
        assert isinstance(record.latency_s, float) and record.latency_s >= 0
        for tokens in (record.prompt_tokens, record.completion_tokens):
            assert tokens is None or (isinstance(tokens, int) and tokens >= 0)
    assert second.response == first.response


def test_every_builtin_backend_is_registered() -> None:
    assert set(BUILDERS) <= set(available_backends())
