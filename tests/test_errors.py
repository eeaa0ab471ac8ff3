"""The error classes and their exit statuses: an LLM service that does not answer this time
is not bad input (exit 3, HTTP 503), and ``except ValueError`` does not catch it."""

from __future__ import annotations

import os
import pickle
import socket
import subprocess
import sys
from collections.abc import Iterator

import pytest

import llm_grop
from cli_support import REQUEST, one_line_error
from llm_grop.cli import main
from llm_grop.errors import BadInput, LLMError, LLMGropError, LLMTransient, LLMUnavailable
from llm_grop.llm.base import BackendOptions
from llm_grop.service.workers import status_of


@pytest.fixture
def closed_port() -> Iterator[int]:
    """A loopback port that is bound but not listening, so connections are refused."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        yield sock.getsockname()[1]


@pytest.fixture(autouse=True)
def _no_ambient_openai_env(monkeypatch: pytest.MonkeyPatch) -> None:
    for name in ("OPENAI_BASE_URL", "OPENAI_API_KEY", "OPENAI_CUSTOM_HEADERS"):
        monkeypatch.delenv(name, raising=False)


def test_a_transient_llm_failure_is_its_own_kind() -> None:
    assert issubclass(LLMTransient, LLMGropError) and LLMTransient.exit_code == 3
    for base in (BadInput, ValueError, LLMError, LLMUnavailable):
        assert not issubclass(LLMTransient, base), base
    # A wrong key or model stays bad input.
    assert issubclass(LLMUnavailable, BadInput) and LLMUnavailable.exit_code == 2
    assert llm_grop.LLMTransient is LLMTransient


def test_a_transient_failure_keeps_its_parameter_through_pickling() -> None:
    exc = LLMTransient("2 trials got no LLM answer", param="max_failed", value=2)
    back = pickle.loads(pickle.dumps(exc))
    assert (type(back), str(back), back.param, back.value, back.detail) == \
        (LLMTransient, "max_failed=2: 2 trials got no LLM answer", "max_failed", 2,
         "2 trials got no LLM answer")
    plain = pickle.loads(pickle.dumps(LLMTransient("cannot reach it")))
    assert (type(plain), str(plain), plain.param) == (LLMTransient, "cannot reach it", None)


def test_the_service_answers_a_transient_failure_503() -> None:
    assert status_of(LLMTransient("openai backend: cannot reach x"))[0] == 503
    assert status_of(LLMUnavailable("openai backend: model 'x' not found"))[0] == 503
    assert status_of(BadInput("nope"))[0] == 422


def test_except_value_error_does_not_catch_it_through_the_api(closed_port: int) -> None:
    options = BackendOptions(base_url=f"http://127.0.0.1:{closed_port}/v1", max_retries=0)
    with pytest.raises(LLMTransient, match="connection refused") as caught:
        try:
            llm_grop.arrange(REQUEST, llm="openai", llm_options=options)
        except ValueError:  # bad input only: a caller's retry logic must not land here
            pytest.fail("an unreachable LLM service was caught as bad input")
    assert "\n" not in str(caught.value)


def test_the_command_exits_3_when_the_llm_service_is_unreachable(closed_port: int) -> None:
    url = f"http://127.0.0.1:{closed_port}/v1"
    done = subprocess.run(
        [sys.executable, "-m", "llm_grop", "arrange", REQUEST, "--llm", "openai",
         "--base-url", url, "--retries", "0", "--timeout", "5", "--no-cache"],
        capture_output=True, text=True, timeout=120,
        env=os.environ | {"OPENAI_API_KEY": "test"})
    assert done.returncode == 3, done.stderr
    assert done.stderr == f"llm-grop: error: openai backend: cannot reach {url} " \
                          "(connection refused) (retries disabled)\n"
    assert done.stdout == ""


def test_the_command_exits_3_when_the_llm_service_times_out(chat_server, capsys,
                                                            monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "test")
    chat_server.delay_s = 3.0
    assert main(["arrange", REQUEST, "--llm", "openai", "--base-url", chat_server.url,
                 "--retries", "0", "--timeout", "0.5", "--no-cache"]) == 3
    line = one_line_error(capsys)
    assert line == f"llm-grop: error: openai backend: cannot reach {chat_server.url} " \
                   "(no answer within the 0.5 s deadline)"
