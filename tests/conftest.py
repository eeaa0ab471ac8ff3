"""A real OpenAI-compatible HTTP server on 127.0.0.1 for the LLM backend tests.

It implements ``POST /v1/chat/completions`` with OpenAI's JSON shapes. By default it
answers 200 with a reply that depends only on the prompt and the seed; tests can
queue other statuses (``server.plan``), require an API key, restrict the models it
knows, or delay answers. Every request body and header set is kept in ``requests``.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler
from typing import Any

import pytest

# MuJoCo reads MUJOCO_GL once, when first imported; the package picks an offscreen backend
# then, so it must come before any test module imports mujoco itself.
import llm_grop.simulation.mujoco  # noqa: F401
from http_support import serving

_ERROR_TYPES = {
    400: ("invalid_request_error", "bad_request"),
    401: ("invalid_request_error", "invalid_api_key"),
    404: ("invalid_request_error", "model_not_found"),
    429: ("rate_limit_error", "rate_limit_exceeded"),
}


def default_reply(body: dict[str, Any]) -> str:
    """The server's answer: a function of the prompt and the seed alone."""
    prompt = body["messages"][-1]["content"]
    return f"reply to {prompt!r} with seed {body.get('seed')}"


@dataclass
class ChatServer:
    """State of the local chat-completions server; ``url`` is its ``/v1`` base URL."""

    url: str = ""
    #: Statuses to answer, in order, before falling back to normal answers.
    plan: deque[int] = field(default_factory=deque)
    #: If set, requests must carry ``Authorization: Bearer <api_key>`` (else 401).
    api_key: str | None = None
    #: If set, other models get 404.
    models: set[str] | None = None
    #: Raw 200 bodies to send, in order, before normal answers (malformed answers).
    raw: deque[bytes] = field(default_factory=deque)
    #: Seconds to wait before answering, to provoke client timeouts.
    delay_s: float = 0.0
    #: Seconds between the bytes of an answer's body (0: all at once): a trickling server.
    trickle_s: float = 0.0
    #: Seconds the answer stops halfway through its body (a server that hangs mid-answer).
    stall_s: float = 0.0
    #: Bytes of padding in a planned failure's message (a server that floods its errors).
    error_bytes: int = 0
    #: The Retry-After header of error answers (default: 10 ms, keeping backoff short).
    retry_after: str | None = None
    reply: Callable[[dict[str, Any]], str] = default_reply
    #: If set, a request asking for structured output (``response_format``) gets 400, as
    #: from a server without it.
    refuse_response_format: bool = False
    requests: list[dict[str, Any]] = field(default_factory=list)
    headers: list[dict[str, str]] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def answer(self, body: dict[str, Any], headers: dict[str, str]
               ) -> tuple[int, dict[str, Any] | bytes]:
        """The status and body (JSON, or raw bytes) for one request."""
        with self.lock:
            self.requests.append(body)
            self.headers.append(headers)
            planned = self.plan.popleft() if self.plan else None
            raw = self.raw.popleft() if self.raw else None
        if raw is not None:
            return 200, raw
        if self.refuse_response_format and "response_format" in body:
            return 400, _error(400, "response_format is not supported")
        if planned is not None and planned != 200:
            return planned, _error(planned, f"planned failure {planned}" + "x" * self.error_bytes)
        if self.api_key is not None and headers.get("authorization") != f"Bearer {self.api_key}":
            return 401, _error(401, "Incorrect API key provided.")
        model = body.get("model")
        if self.models is not None and model not in self.models:
            return 404, _error(404, f"The model `{model}` does not exist.")
        text = self.reply(body)
        prompt = body["messages"][-1]["content"]
        prompt_tokens, completion_tokens = len(prompt.split()), len(text.split())
        return 200, {
            "id": f"chatcmpl-{len(self.requests)}",
            "object": "chat.completion",
            "created": 1_700_000_000,
            "model": model,
            "choices": [{
                "index": 0,
                "message": {"role": "assistant", "content": text},
                "finish_reason": "stop",
                "logprobs": None,
            }],
            "usage": {
                "prompt_tokens": prompt_tokens,
                "completion_tokens": completion_tokens,
                "total_tokens": prompt_tokens + completion_tokens,
            },
        }


def _error(status: int, message: str) -> dict[str, Any]:
    kind, code = _ERROR_TYPES.get(status, ("server_error", None))
    return {"error": {"message": message, "type": kind, "param": None, "code": code}}


def _handler(state: ChatServer) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        protocol_version = "HTTP/1.1"

        def do_GET(self) -> None:
            if self.path.rstrip("/") != "/v1/models":
                self._send(404, {"error": {"message": f"no route {self.path}"}})
                return
            names = sorted(state.models) if state.models is not None else ["local-model"]
            self._send(200, {"object": "list", "data": [
                {"id": name, "object": "model", "owned_by": "test"} for name in names]})

        def do_POST(self) -> None:
            length = int(self.headers.get("content-length", "0"))
            raw = self.rfile.read(length)
            if self.path.rstrip("/") != "/v1/chat/completions":
                self._send(404, {"error": {"message": f"no route {self.path}"}})
                return
            headers = {k.lower(): v for k, v in self.headers.items()}
            status, body = state.answer(json.loads(raw), headers)
            if state.delay_s:
                time.sleep(state.delay_s)
            self._send(status, body)

        def _send(self, status: int, body: dict[str, Any] | bytes) -> None:
            data = body if isinstance(body, bytes) else json.dumps(body).encode()
            # A client that timed out has hung up already.
            with contextlib.suppress(BrokenPipeError, ConnectionResetError):
                self.send_response(status)
                self.send_header("content-type", "application/json")
                self.send_header("content-length", str(len(data)))
                if status != 200 and state.retry_after is not None:
                    self.send_header("retry-after", state.retry_after)
                elif status != 200:
                    # Keeps the retry backoff short.
                    self.send_header("retry-after-ms", "10")
                self.end_headers()
                if state.stall_s:
                    self.wfile.write(data[:len(data) // 2])
                    self.wfile.flush()
                    time.sleep(state.stall_s)
                    self.wfile.write(data[len(data) // 2:])
                    return
                if not state.trickle_s:
                    self.wfile.write(data)
                    return
                for k in range(len(data)):
                    self.wfile.write(data[k:k + 1])
                    self.wfile.flush()
                    time.sleep(state.trickle_s)

        def log_message(self, format: str, *args: Any) -> None:
            pass

    return Handler


def pytest_configure(config: pytest.Config) -> None:
    """The tests' LLM answer cache is a fresh directory, never the user's; ``--llm auto``
    probes no port of the machine (a test that wants it names its own server's), so that
    no server a developer runs changes a test's LLM."""
    os.environ["LLM_GROP_CACHE_DIR"] = tempfile.mkdtemp(prefix="llm-grop-test-cache-")
    os.environ["LLM_GROP_PROBE_PORTS"] = ""
    for name in ("OPENAI_BASE_URL", "OPENAI_API_KEY"):
        os.environ.pop(name, None)


def pytest_unconfigure(config: pytest.Config) -> None:
    shutil.rmtree(os.environ.pop("LLM_GROP_CACHE_DIR", ""), ignore_errors=True)


@pytest.fixture
def chat_server() -> Iterator[ChatServer]:
    """A running local chat-completions server, stopped after the test."""
    state = ChatServer()
    with serving(_handler(state)) as root:
        state.url = f"{root}/v1"
        yield state
