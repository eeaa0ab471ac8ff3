"""The openai backend against a real local OpenAI-compatible HTTP server."""

from __future__ import annotations

import contextlib
import socket
import time
from collections import deque
from collections.abc import Iterator
from typing import TYPE_CHECKING

import pytest

from llm_grop.errors import LLMAnswerUnusable, LLMTransient, LLMUnavailable
from llm_grop.llm.base import BackendOptions, SamplingParams
from llm_grop.llm.openai_backend import DEFAULT_MODEL, PLACEHOLDER_API_KEY, OpenAILLM
from llm_grop.llm.registry import create_llm

if TYPE_CHECKING:
    from conftest import ChatServer

PARAMS = SamplingParams(temperature=0.1, top_p=0.9, max_tokens=64, frequency_penalty=0.2,
                        presence_penalty=0.3, seed=7)


@pytest.fixture(autouse=True)
def _no_ambient_openai_env(monkeypatch: pytest.MonkeyPatch) -> None:
    for name in ("OPENAI_BASE_URL", "OPENAI_API_KEY", "OPENAI_CUSTOM_HEADERS"):
        monkeypatch.delenv(name, raising=False)


@pytest.fixture
def closed_port() -> Iterator[int]:
    """A local port that is bound but not listening, so connections are refused."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        yield sock.getsockname()[1]


def make(server: ChatServer, **options: object) -> OpenAILLM:
    llm = OpenAILLM(BackendOptions(base_url=server.url, **options))  # type: ignore[arg-type]
    return llm


def test_sends_sampling_params_and_records_the_answer(chat_server: ChatServer) -> None:
    llm = make(chat_server, model="local-model")
    record = llm.complete("Where does the fork go?", PARAMS)
    body = chat_server.requests[-1]
    assert body["model"] == "local-model"
    assert body["messages"] == [{"role": "user", "content": "Where does the fork go?"}]
    assert (body["temperature"], body["top_p"], body["max_tokens"]) == (0.1, 0.9, 64)
    assert (body["frequency_penalty"], body["presence_penalty"], body["seed"]) == (0.2, 0.3, 7)
    assert record.backend == "openai"
    assert record.model == "local-model"
    assert record.prompt == "Where does the fork go?"
    assert record.response == "reply to 'Where does the fork go?' with seed 7"
    assert (record.prompt_tokens, record.completion_tokens) == (5, 10)
    assert record.seed == 7
    assert record.latency_s > 0
    llm.close()


def test_no_seed_sends_no_seed(chat_server: ChatServer) -> None:
    record = make(chat_server).complete("hi", SamplingParams())
    assert "seed" not in chat_server.requests[-1]
    assert record.seed is None


def test_grammar_is_ignored(chat_server: ChatServer) -> None:
    record = make(chat_server).complete("hi", PARAMS, grammar='root ::= "x"')
    assert "grammar" not in chat_server.requests[-1]
    assert record.response == "reply to 'hi' with seed 7"


def test_default_model_and_placeholder_key(chat_server: ChatServer) -> None:
    llm = make(chat_server)
    llm.complete("hi", PARAMS)
    assert llm.model == DEFAULT_MODEL == "gpt-4o-mini"
    assert chat_server.requests[-1]["model"] == "gpt-4o-mini"
    assert chat_server.headers[-1]["authorization"] == f"Bearer {PLACEHOLDER_API_KEY}"


def test_environment_gives_base_url_and_key(chat_server: ChatServer,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OPENAI_BASE_URL", chat_server.url)
    monkeypatch.setenv("OPENAI_API_KEY", "sk-from-env")
    chat_server.api_key = "sk-from-env"
    llm = create_llm("openai", BackendOptions(model="m"))
    assert isinstance(llm, OpenAILLM)
    assert llm.base_url == chat_server.url
    assert llm.complete("hi", PARAMS).response == "reply to 'hi' with seed 7"
    assert len(chat_server.requests) == 1


def test_option_overrides_environment(chat_server: ChatServer, closed_port: int,
                                      monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OPENAI_BASE_URL", f"http://127.0.0.1:{closed_port}/v1")
    assert make(chat_server).complete("hi", PARAMS).response.startswith("reply to")


def test_retries_recover_from_500_and_429(chat_server: ChatServer) -> None:
    chat_server.plan = deque([500, 429])
    record = make(chat_server, max_retries=3).complete("hi", PARAMS)
    assert record.response == "reply to 'hi' with seed 7"
    assert len(chat_server.requests) == 3
    assert all(body == chat_server.requests[0] for body in chat_server.requests)


def test_exhausted_retries_are_transient(chat_server: ChatServer) -> None:
    chat_server.plan = deque([503, 503, 503, 503])
    with pytest.raises(LLMTransient) as caught:
        make(chat_server, max_retries=2).complete("hi", PARAMS)
    message = str(caught.value)
    assert len(chat_server.requests) == 3
    assert "503" in message and "planned failure 503" in message
    assert "after 2 retries" in message
    assert "\n" not in message


def test_unreachable_endpoint(closed_port: int) -> None:
    url = f"http://127.0.0.1:{closed_port}/v1"
    llm = OpenAILLM(BackendOptions(base_url=url, max_retries=1, timeout_s=5))
    with pytest.raises(LLMTransient) as caught:
        llm.complete("hi", PARAMS)
    assert str(caught.value) == (
        f"openai backend: cannot reach {url} (connection refused) after 1 retry")


def test_unreachable_without_retries_says_so(closed_port: int) -> None:
    url = f"http://127.0.0.1:{closed_port}/v1"
    with pytest.raises(LLMTransient, match=r"connection refused\) \(retries disabled\)$"):
        OpenAILLM(BackendOptions(base_url=url, max_retries=0)).complete("hi", PARAMS)


def test_timeout_is_transient(chat_server: ChatServer) -> None:
    chat_server.delay_s = 1.0
    llm = make(chat_server, timeout_s=0.1, max_retries=0)
    with pytest.raises(LLMTransient,
                       match=r"cannot reach .* \(no answer within the 0.1 s deadline\)"):
        llm.complete("hi", PARAMS)


def test_refused_key(chat_server: ChatServer) -> None:
    chat_server.api_key = "sk-right"
    with pytest.raises(LLMUnavailable) as caught:
        make(chat_server, api_key="sk-wrong").complete("hi", PARAMS)
    message = str(caught.value)
    assert "API key was refused" in message and "401" in message
    assert "\n" not in message
    assert len(chat_server.requests) == 1, "a refused key is not retried"


def test_unknown_model(chat_server: ChatServer) -> None:
    chat_server.models = {"known"}
    with pytest.raises(LLMUnavailable) as caught:
        make(chat_server, model="no-such-model").complete("hi", PARAMS)
    message = str(caught.value)
    assert "model 'no-such-model' not found" in message and "404" in message
    assert "does not exist" in message


def test_other_api_error_gives_status_and_message(chat_server: ChatServer) -> None:
    chat_server.plan = deque([400])
    with pytest.raises(LLMUnavailable) as caught:
        make(chat_server).complete("hi", PARAMS)
    message = str(caught.value)
    assert message == f"openai backend: {chat_server.url} answered 400 (planned failure 400)"
    assert "Traceback" not in message


@pytest.mark.parametrize("body", [b"not json", b'{"foo": 1}', b'{"choices": []}',
                                  b'{"choices": [{"index": 0}]}', b'{"choices": "x"}'])
def test_malformed_answer_is_one_line(chat_server: ChatServer, body: bytes) -> None:
    chat_server.raw = deque([body])
    # Text that is no JSON is garbled on the way (transient); JSON without a reply is an
    # unusable answer, which a bench keeps as a failed trial (the next may be whole), not
    # a lasting fault of the configuration.
    kind = LLMTransient if body == b"not json" else LLMAnswerUnusable
    with pytest.raises(kind) as caught:
        make(chat_server).complete("hi", PARAMS)
    assert not isinstance(caught.value, LLMUnavailable)
    message = str(caught.value)
    assert message.startswith("openai backend: ")
    assert "answer from " + chat_server.url in message
    assert "\n" not in message


@pytest.mark.parametrize("body", [b'{"error": {"message": "upstream\\nbusy"}}',
                                  b'{"error": "upstream busy"}'])
def test_an_error_in_a_200_answer_is_quoted(chat_server: ChatServer, body: bytes) -> None:
    chat_server.raw = deque([body])
    with pytest.raises(LLMAnswerUnusable) as caught:
        make(chat_server).complete("hi", PARAMS)
    assert str(caught.value) == (f"openai backend: malformed answer from {chat_server.url}: "
                                 "no text in choices[0].message.content (the server said: "
                                 "upstream busy)")


def test_answer_without_usage_has_no_token_counts(chat_server: ChatServer) -> None:
    chat_server.raw = deque([b'{"choices": [{"index": 0, "message": {"role": "assistant", '
                             b'"content": "ok"}}]}'])
    record = make(chat_server).complete("hi", PARAMS)
    assert (record.response, record.prompt_tokens, record.completion_tokens) == ("ok", None, None)


def test_a_trickling_server_is_bounded_by_the_whole_calls_deadline(
        chat_server: ChatServer) -> None:
    chat_server.trickle_s = 0.05  # a 400-byte answer would take 20 s
    llm = make(chat_server, timeout_s=1.0, max_retries=2)
    t0 = time.monotonic()
    with pytest.raises(LLMTransient, match=r"no answer within the 1 s deadline"):
        llm.complete("hi", PARAMS)
    assert time.monotonic() - t0 < 1.5


def test_a_retry_after_past_the_deadline_is_not_waited_for(chat_server: ChatServer) -> None:
    chat_server.plan.extend([429, 429, 429])
    chat_server.retry_after = "50"
    llm = make(chat_server, timeout_s=3.0, max_retries=2)
    t0 = time.monotonic()
    with pytest.raises(LLMTransient) as info:
        llm.complete("hi", PARAMS)
    assert time.monotonic() - t0 < 1.0 and len(chat_server.requests) == 1
    assert str(info.value).endswith("its next attempt (50.0 s later) would pass the 3 s "
                                    "deadline")
    assert "answered 429" in str(info.value)


def test_a_huge_answer_is_refused_as_it_arrives(chat_server: ChatServer) -> None:
    chat_server.reply = lambda body: "x" * (5 * 1024 * 1024)
    llm = OpenAILLM(BackendOptions(base_url=chat_server.url, max_answer_bytes=1024 * 1024))
    with pytest.raises(LLMAnswerUnusable, match=r"is larger than 1048576 bytes; refused"):
        llm.complete("hi", PARAMS)


def test_a_huge_error_answer_is_refused_as_it_arrives(chat_server: ChatServer) -> None:
    chat_server.plan.extend([500])
    chat_server.error_bytes = 5 * 1024 * 1024
    llm = OpenAILLM(BackendOptions(base_url=chat_server.url, max_answer_bytes=1024 * 1024,
                                   max_retries=2))
    with pytest.raises(LLMAnswerUnusable, match=r"is larger than 1048576 bytes; refused"):
        llm.complete("hi", PARAMS)
    assert len(chat_server.requests) == 1  # refused, not asked again


def test_a_trickled_error_answer_is_cut_off_at_the_deadline(chat_server: ChatServer) -> None:
    # 2 kB at 5 ms a byte would take 10 s, each byte well within any read timeout.
    chat_server.plan.extend([503])
    chat_server.error_bytes = 2000
    chat_server.trickle_s = 0.005
    with pytest.raises(LLMTransient, match=r"no answer within the 1 s deadline"):
        make(chat_server, timeout_s=1.0, max_retries=0).complete("hi", PARAMS)


def test_an_answer_that_stops_halfway_is_one_line_at_the_deadline(
        chat_server: ChatServer) -> None:
    chat_server.stall_s = 3.0
    with pytest.raises(LLMTransient, match=r"no answer within the 1 s deadline"):
        make(chat_server, timeout_s=1.0, max_retries=0).complete("hi", PARAMS)


def test_a_retry_after_that_is_no_number_or_date_falls_back_to_backoff(
        chat_server: ChatServer) -> None:
    chat_server.plan.extend([429])
    chat_server.retry_after = "soon"
    record = make(chat_server, max_retries=1, timeout_s=10).complete("hi", PARAMS)
    assert record.response and len(chat_server.requests) == 2


def test_passing_failures_are_transient_and_lasting_ones_are_not(chat_server: ChatServer,
                                                                 closed_port: int) -> None:
    chat_server.plan.extend([500])
    with pytest.raises(LLMTransient, match="answered 500"):
        make(chat_server, max_retries=0).complete("hi", PARAMS)
    with pytest.raises(LLMTransient, match="connection refused"):
        OpenAILLM(BackendOptions(base_url=f"http://127.0.0.1:{closed_port}/v1",
                                 max_retries=0)).complete("hi", PARAMS)
    chat_server.api_key = "right"
    with pytest.raises(LLMUnavailable) as info:
        make(chat_server, max_retries=0, api_key="wrong").complete("hi", PARAMS)
    assert not isinstance(info.value, LLMTransient)


@pytest.fixture
def hostile() -> Iterator[tuple[str, list[str]]]:
    """A loopback server that misbehaves as told: ``"headers"`` trickles its status line
    and headers a byte every 0.2 s (for half an hour), ``"silent"`` reads the request and
    never answers. Yields its /v1 URL and the list to append the behaviour to."""
    import threading

    behaviour: list[str] = []
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(16)
    stop = threading.Event()

    def one(conn: socket.socket) -> None:
        with conn, contextlib.suppress(OSError):
            conn.recv(65536)
            if behaviour[-1] == "headers":
                for byte in b"HTTP/1.1 200 OK\r\nX-Slow: " + b"a" * 10_000:
                    if stop.is_set():
                        return
                    conn.sendall(bytes([byte]))
                    time.sleep(0.2)
            stop.wait(1800)

    def serve() -> None:
        with contextlib.suppress(OSError):
            while True:
                conn, _ = srv.accept()
                threading.Thread(target=one, args=(conn,), daemon=True).start()

    threading.Thread(target=serve, daemon=True).start()
    yield f"http://127.0.0.1:{srv.getsockname()[1]}/v1", behaviour
    stop.set()
    srv.close()


@pytest.mark.parametrize("behaviour", ["headers", "silent"])
def test_a_server_that_trickles_its_headers_or_says_nothing_is_cut_at_the_deadline(
        hostile: tuple[str, list[str]], behaviour: str) -> None:
    url, told = hostile
    told.append(behaviour)
    llm = OpenAILLM(BackendOptions(base_url=url, timeout_s=1.0, max_retries=2))
    start = time.monotonic()
    with pytest.raises(LLMTransient) as err:
        llm.complete("Where does the fork go?", PARAMS)
    # The server would hold the call for half an hour; the deadline ends it.
    assert time.monotonic() - start < 30
    assert "no answer within the 1 s deadline" in str(err.value)
    llm.close()
