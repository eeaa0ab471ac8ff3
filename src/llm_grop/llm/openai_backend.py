"""The ``openai`` backend: any OpenAI-compatible chat-completions endpoint.

It speaks to api.openai.com or to a local server with the same API (vLLM, Ollama,
llama.cpp server) through the official ``openai`` SDK.

- Endpoint: ``BackendOptions.base_url``, else the ``OPENAI_BASE_URL`` environment
  variable, else ``https://api.openai.com/v1`` (the SDK's own resolution).
- API key: ``BackendOptions.api_key``, else ``OPENAI_API_KEY``, else the placeholder
  :data:`PLACEHOLDER_API_KEY`, which local servers accept and OpenAI refuses (401).
- Model: ``BackendOptions.model``, else :data:`DEFAULT_MODEL`.
- A deadline: ``BackendOptions.timeout_s`` bounds the whole call, every attempt, the
  reading of each answer's headers and body (an error's or a redirect's too) and the
  waits between attempts included, so a server that trickles its headers or its answer a
  byte at a time, says nothing, or asks to be retried much later, cannot hold a run
  longer than that: at the deadline the attempt's socket is shut (:class:`Cutoff`),
  whatever is being read, and a wait that would pass it is not waited for.
- Retries: connection errors, 408, 409, 429 and 5xx answers are retried up to
  ``max_retries`` times with exponential backoff (0.5 s doubling to at most 8 s, with
  jitter), honouring the server's ``retry-after-ms`` and ``retry-after`` headers, as
  long as the deadline allows.
- A size cap: an answer larger than ``BackendOptions.max_answer_bytes``, an error's
  included, is refused as it arrives.
- Grammars: chat-completions has no GBNF support, so ``grammar`` is ignored.
- Structured output: given a ``schema``, the request asks for JSON that follows it
  (``response_format`` of type ``json_schema``, strict). A server that turns this down
  with 400 or 422 is asked again without it, and not asked with a schema again by this
  client; the prompts ask for a format the tolerant readers take either way.
"""

from __future__ import annotations

import json
import math
import os
import random
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import httpx
import openai

from llm_grop.errors import LLMAnswerUnusable, LLMError, LLMTransient, LLMUnavailable
from llm_grop.llm.base import BackendOptions, BaseLLM, SamplingParams
from llm_grop.llm.openai_wire import (
    HTTP_ERRORS,
    TIMEOUTS,
    Cutoff,
    detail,
    one_line,
    retry_after_s,
    root_cause,
)
from llm_grop.llm.record import LLMCallRecord

#: The model used when ``BackendOptions.model`` is ``None``.
DEFAULT_MODEL = "gpt-4o-mini"

#: The API key sent when none is configured; local servers ignore it.
PLACEHOLDER_API_KEY = "not-needed"

@dataclass(frozen=True)
class OpenAIOptions:
    """The openai backend's own options.

    ``structured_output``: ask the server for answers that follow a JSON Schema
    (``response_format``); ``false`` sends the prompt's own format alone, for servers
    that mishandle the schema rather than turn it down.
    """

    structured_output: bool = True


class OpenAILLM(BaseLLM):
    """A chat model behind an OpenAI-compatible HTTP endpoint.

    ``complete`` sends the prompt as one user message. The record's ``latency_s`` is
    the wall time of the whole request in seconds, retries and backoff included.
    """

    backend: str = "openai"
    Options = OpenAIOptions

    def __init__(self, options: BackendOptions) -> None:
        self.model: str = options.model or DEFAULT_MODEL
        #: Whether calls ask for structured output (its option ``structured_output``).
        self.supports_schema: bool = self.own_options(options).structured_output
        api_key = options.api_key or os.environ.get("OPENAI_API_KEY") or PLACEHOLDER_API_KEY
        self._max_retries = options.max_retries
        self._timeout_s = options.timeout_s
        self._max_bytes = options.max_answer_bytes
        #: When this thread's latest call must end (``deadline``, a :func:`time.monotonic`
        #: time), which the response hook reads: per thread, as calls in two threads have
        #: deadlines of their own.
        self._call = threading.local()
        self._jitter = random.Random()
        try:
            # base_url=None lets the SDK read OPENAI_BASE_URL.
            # Retries are this module's, within the call's deadline.
            self._client = openai.OpenAI(
                base_url=options.base_url or None,
                api_key=api_key,
                timeout=options.timeout_s,
                max_retries=0,
                # A fresh connection per request, so that each attempt's socket is known
                # to its deadline (:meth:`_trace`); an LLM call outlasts a handshake.
                http_client=openai.DefaultHttpxClient(
                    limits=httpx.Limits(max_keepalive_connections=0),
                    event_hooks={"request": [self._traced],
                                 "response": [self._read_other_body]}),
            )
        except (openai.OpenAIError, ValueError, TypeError) as exc:
            raise LLMUnavailable(f"openai backend: cannot configure the client: {one_line(exc)}"
                                 ) from None
        #: The endpoint in use, without a trailing slash.
        self.base_url: str = str(self._client.base_url).rstrip("/")
        #: What the LLM cache keys this backend's answers by: the endpoint and the model.
        self.cache_identity: str = f"openai:{self.base_url}:{self.model}"
        #: ``False`` once the server turned structured output down.
        self.structured_output: bool | None = None

    def complete(self, prompt: str, params: SamplingParams, grammar: str | None = None,
                 schema: Mapping[str, Any] | None = None) -> LLMCallRecord:
        """Send ``prompt`` and return the call's record; ``grammar`` is ignored, ``schema``
        asks for structured output where the server supports it."""
        kwargs: dict[str, Any] = {
            "model": self.model,
            "messages": [{"role": "user", "content": prompt}],
            "temperature": params.temperature,
            "top_p": params.top_p,
            "max_tokens": params.max_tokens,
            "frequency_penalty": params.frequency_penalty,
            "presence_penalty": params.presence_penalty,
        }
        if params.seed is not None:
            kwargs["seed"] = params.seed
        if schema is not None and self.structured_output is not False:
            kwargs["response_format"] = {"type": "json_schema", "json_schema": {
                "name": "answer", "schema": dict(schema), "strict": True}}
        start = time.perf_counter()
        deadline = self._call.deadline = time.monotonic() + self._timeout_s
        try:
            response = self._retried(kwargs, deadline)
        except (openai.BadRequestError, openai.UnprocessableEntityError) as exc:
            if "response_format" not in kwargs:
                raise self._unavailable(exc) from None
            # The server has no structured output; the prompt's own format still reads.
            self.structured_output = False
            del kwargs["response_format"]
            try:
                response = self._retried(kwargs, deadline)
            except openai.OpenAIError as exc:
                raise self._unavailable(exc) from None
            except (ValueError, RecursionError) as exc:
                raise LLMTransient(f"openai backend: unreadable answer from {self.base_url}: "
                                   f"{one_line(exc)}") from None
        except openai.OpenAIError as exc:
            raise self._unavailable(exc) from None
        except (ValueError, RecursionError) as exc:
            # A 200 answer whose body is not JSON.
            raise LLMTransient(f"openai backend: unreadable answer from {self.base_url}: "
                                 f"{one_line(exc)}") from None
        else:
            if "response_format" in kwargs:
                self.structured_output = True
        latency_s = time.perf_counter() - start
        text, prompt_tokens, completion_tokens = self._read(response)
        return LLMCallRecord(
            backend=self.backend,
            model=self.model,
            prompt=prompt,
            response=text,
            latency_s=latency_s,
            prompt_tokens=prompt_tokens,
            completion_tokens=completion_tokens,
            seed=params.seed,
        )

    def _retried(self, kwargs: dict[str, Any], deadline: float) -> Any:
        """The answer's JSON, asked up to ``1 + max_retries`` times before ``deadline``
        (a :func:`time.monotonic` time); the last failure is raised."""
        attempt = 0
        while True:
            try:
                return self._attempt(kwargs, deadline)
            except (openai.APIConnectionError, openai.APIStatusError) as exc:
                retryable = isinstance(exc, openai.APIConnectionError) and not isinstance(
                    exc, openai.APITimeoutError) or isinstance(exc, openai.APIStatusError) and (
                    exc.status_code in (408, 409, 429) or exc.status_code >= 500)
                if not retryable or attempt >= self._max_retries:
                    raise
                wait = self._wait(exc, attempt)
                if time.monotonic() + wait >= deadline:
                    raise _PastDeadline(exc, wait) from None
                time.sleep(wait)
                attempt += 1

    def _attempt(self, kwargs: dict[str, Any], deadline: float) -> Any:
        """One request; its answer read as it arrives, within ``deadline`` and the size
        cap."""
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            raise openai.APITimeoutError(request=None)  # type: ignore[arg-type]
        # httpx's timeouts bound each read, so a server that trickles its headers a byte
        # at a time would hold the call for ever: at the deadline the socket is shut.
        cutoff = self._call.cutoff = Cutoff()
        timer = threading.Timer(remaining, cutoff.cut)
        timer.daemon = True
        timer.start()
        try:
            return self._answer(kwargs, deadline, remaining)
        except openai.APIConnectionError:
            if cutoff.fired:
                raise openai.APITimeoutError(request=None) from None  # type: ignore[arg-type]
            raise
        finally:
            timer.cancel()
            self._call.cutoff = None

    def _answer(self, kwargs: dict[str, Any], deadline: float, remaining: float) -> Any:
        """:meth:`_attempt`'s request and its answer's JSON."""
        try:
            with self._client.chat.completions.with_streaming_response.create(
                    **kwargs, timeout=remaining) as raw:
                chunks, size = [], 0
                try:
                    for chunk in raw.iter_bytes():
                        size += len(chunk)
                        if size > self._max_bytes:
                            raise _TooLarge(size)
                        if time.monotonic() > deadline:
                            raise openai.APITimeoutError(request=None)  # type: ignore[arg-type]
                        chunks.append(chunk)
                except TIMEOUTS:
                    raise openai.APITimeoutError(request=None) from None  # type: ignore[arg-type]
                except HTTP_ERRORS as exc:
                    # The connection broke in the middle of the answer: as if it never came.
                    raise openai.APIConnectionError(
                        message=one_line(exc),
                        request=httpx.Request("POST", self.base_url)) from None
        except openai.APIConnectionError as exc:
            # SDKs before 2.31 wrap an error raised in a response hook (:meth:`_read_other_
            # body`) as a connection error, which would be retried; it is the hook's.
            if isinstance(exc.__cause__, openai.OpenAIError):
                raise exc.__cause__ from None
            raise
        return json.loads(b"".join(chunks))

    def _traced(self, request: httpx.Request) -> None:
        """Have httpcore report the request's connection to :meth:`_trace`."""
        request.extensions["trace"] = self._trace

    def _trace(self, event: str, info: dict[str, Any]) -> None:
        """httpcore's report of a request's progress: the new connection's socket is handed
        to this thread's attempt, which shuts it at the deadline."""
        cutoff = getattr(self._call, "cutoff", None)
        if event == "connection.connect_tcp.complete" and cutoff is not None:
            stream = info.get("return_value")
            if stream is not None:
                cutoff.watch(stream.get_extra_info("socket"))

    def _read_other_body(self, response: httpx.Response) -> None:
        """Read the body of an answer other than a success (an error, a redirect) within
        the call's deadline and the size cap: the SDK and httpx read such bodies whole,
        with no cap and a timeout per read only. A success's body is :meth:`_attempt`'s."""
        if response.status_code < 300:
            return
        body = bytearray()
        for chunk in response.iter_bytes():
            body += chunk
            if len(body) > self._max_bytes:
                response.close()
                raise _TooLarge(len(body))
            if time.monotonic() > getattr(self._call, "deadline", math.inf):
                response.close()
                raise openai.APITimeoutError(request=response.request)
        # httpx has no public way to hand back a body read in pieces; read() and .text
        # return what is stored here.
        response._content = bytes(body)

    def _wait(self, exc: Exception, attempt: int) -> float:
        """Seconds before the next attempt: the server's Retry-After, else backoff."""
        response = getattr(exc, "response", None)
        headers = getattr(response, "headers", None) or {}
        for name, scale in (("retry-after-ms", 0.001), ("retry-after", 1.0)):
            wait = retry_after_s(headers.get(name), scale)
            if wait is not None:
                return wait
        return min(0.5 * 2 ** attempt, 8.0) * self._jitter.uniform(0.75, 1.0)

    def _read(self, response: Any) -> tuple[str, int | None, int | None]:
        """The reply text and token counts from the answer's JSON; answers are checked
        here, not trusted."""
        try:
            text = response["choices"][0]["message"]["content"]
            if text is not None and not isinstance(text, str):
                raise TypeError(type(text))
        except (AttributeError, IndexError, KeyError, TypeError):
            # A proxy or a busy server may say 200 and put its error in the body; the next
            # answer may be whole, so a bench keeps the trial as failed and goes on.
            said = _said(response)
            raise LLMAnswerUnusable(f"openai backend: malformed answer from {self.base_url}: "
                                    "no text in choices[0].message.content"
                                    + (f" (the server said: {said})" if said else "")
                                    ) from None
        usage = response.get("usage") if isinstance(response, dict) else None
        usage = usage if isinstance(usage, dict) else {}
        counts = [usage.get(key) for key in ("prompt_tokens", "completion_tokens")]
        prompt_tokens, completion_tokens = (
            n if isinstance(n, int) and not isinstance(n, bool) else None for n in counts)
        # A refusal or a tool call leaves content empty; an empty reply is still a reply.
        return text or "", prompt_tokens, completion_tokens

    def close(self) -> None:
        """Close the HTTP connections; the backend is unusable afterwards."""
        self._client.close()

    def _unavailable(self, exc: openai.OpenAIError) -> LLMError | LLMTransient:
        """The one-line error for a failed request."""
        where = self.base_url
        if isinstance(exc, _TooLarge):
            return LLMAnswerUnusable(f"openai backend: the answer from {where} is larger than "
                                  f"{self._max_bytes} bytes; refused (raise "
                                  "max_answer_bytes=N if it should be allowed)",
                                  mentions=("max_answer_bytes",))
        if isinstance(exc, _PastDeadline):
            first = self._unavailable(exc.cause)
            return LLMTransient(f"{str(first).removesuffix(self._after_retries())}; its "
                                  f"next attempt ({exc.wait_s:.1f} s later) would pass the "
                                  f"{self._timeout_s:g} s deadline")
        if isinstance(exc, openai.APITimeoutError):
            reason = f"no answer within the {self._timeout_s:g} s deadline"
            return LLMTransient(f"openai backend: cannot reach {where} ({reason})")
        if isinstance(exc, openai.APIConnectionError):
            return LLMTransient(f"openai backend: cannot reach {where} "
                                  f"({root_cause(exc)}){self._after_retries()}")
        if isinstance(exc, openai.AuthenticationError):
            return LLMUnavailable(f"openai backend: the API key was refused by {where} (401: "
                                  f"{detail(exc)}); set OPENAI_API_KEY or pass an api_key")
        if isinstance(exc, openai.PermissionDeniedError):
            return LLMUnavailable(f"openai backend: the API key may not use model {self.model!r} "
                                  f"at {where} (403: {detail(exc)})")
        if isinstance(exc, openai.NotFoundError):
            return LLMUnavailable(f"openai backend: model {self.model!r} not found at {where} "
                                  f"(404: {detail(exc)}); check the model name and base URL")
        if isinstance(exc, openai.APIStatusError):
            status = exc.status_code
            transient = status in (408, 409, 429) or status >= 500
            kind = LLMTransient if transient else LLMUnavailable
            return kind(f"openai backend: {where} answered {status} "
                        f"({detail(exc)}){self._after_retries() if transient else ''}")
        return LLMUnavailable(f"openai backend: unexpected answer from {where}: {one_line(exc)}")

    def _after_retries(self) -> str:
        n = self._max_retries
        if n == 0:
            return " (retries disabled)"
        return f" after {n} {'retry' if n == 1 else 'retries'}"


def _said(response: Any) -> str:
    """The error message a 200 answer's JSON carries (``{"error": {"message": ...}}`` or
    ``{"error": "..."}``), on one line; empty if none."""
    error = response.get("error") if isinstance(response, dict) else None
    message = error.get("message") if isinstance(error, dict) else error
    return one_line(message) if isinstance(message, str) else ""


class _TooLarge(openai.OpenAIError):
    """An answer over the size cap (bytes received so far)."""

    def __init__(self, size: int) -> None:
        super().__init__(f"{size} bytes")


class _PastDeadline(openai.OpenAIError):
    """A retryable failure whose next attempt would come after the call's deadline."""

    def __init__(self, cause: openai.OpenAIError, wait_s: float) -> None:
        super().__init__(str(cause))
        self.cause, self.wait_s = cause, wait_s
