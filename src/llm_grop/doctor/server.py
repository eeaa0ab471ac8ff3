"""The check of a configured OpenAI-compatible server (it answers ``GET /models`` and
lists the model), and of what ``--llm auto`` would use. The only network access the
doctor makes: to the server the user configured, and ``auto``'s bounded probe of
127.0.0.1's usual ports."""

from __future__ import annotations

import json
import shlex

import httpx

from llm_grop.doctor.check import Check, Status, one_line
from llm_grop.errors import LLMUnavailable
from llm_grop.llm.auto import bounded_get, choose

#: How long the server has to answer, in seconds.
SERVER_TIMEOUT_S = 5.0

#: Most model names quoted when the wanted one is missing.
_MAX_LISTED = 8
#: Most characters of a name or reason from the server shown on the report's line.
_MAX_SHOWN = 120
_NAME = "openai server"


def check_server(base_url: str | None, model: str | None, api_key: str | None,
                 timeout_s: float = SERVER_TIMEOUT_S) -> Check:
    """Whether the OpenAI-compatible server at ``base_url`` (its ``/v1`` root) answers and
    lists ``model`` (``None``: the openai backend's default); skipped without a server."""
    if not base_url:
        return Check(_NAME, Status.SKIP, "skipped (none configured; --base-url or "
                     "OPENAI_BASE_URL names one)")
    from llm_grop.llm.openai_backend import DEFAULT_MODEL, PLACEHOLDER_API_KEY

    model = model or DEFAULT_MODEL
    root = one_line(_without_password(base_url.rstrip("/")))[:_MAX_SHOWN]
    key = api_key or PLACEHOLDER_API_KEY
    if not key.isascii():
        return Check(_NAME, Status.FAIL, "the API key holds characters other than ASCII, "
                     "which no HTTP header can carry", "export OPENAI_API_KEY=<the key, "
                     "as the server issued it>")
    try:
        status, body = bounded_get(f"{base_url.rstrip('/')}/models", key, timeout_s)
    except (httpx.HTTPError, httpx.InvalidURL, TimeoutError, ValueError) as exc:
        reason = one_line(str(exc))[:_MAX_SHOWN] or type(exc).__name__
        return Check(_NAME, Status.FAIL, f"{root}: unreachable ({reason})",
                     "start the server, or: export OPENAI_BASE_URL=<its /v1 URL>")
    if status in (401, 403):
        return Check(_NAME, Status.FAIL, f"{root}: GET /models refused the API key "
                     f"({status})", "export OPENAI_API_KEY=<the server's key>")
    if status != 200:
        return Check(_NAME, Status.FAIL, f"{root}: GET /models answered "
                     f"{status}; is this the API's root (ending in /v1)?",
                     "export OPENAI_BASE_URL=http://<host>:<port>/v1")
    try:
        listed = [one_line(str(entry["id"]))[:_MAX_SHOWN]
                  for entry in json.loads(body)["data"]]
    except (ValueError, KeyError, TypeError, RecursionError):
        return Check(_NAME, Status.FAIL, f"{root}: the answer to GET /models is not a list "
                     "of models", "export OPENAI_BASE_URL=http://<host>:<port>/v1")
    if model not in listed:
        shown = ", ".join(listed[:_MAX_LISTED]) + (", ..." if len(listed) > _MAX_LISTED
                                                   else "")
        fix = f"pass --model {shlex.quote(listed[0])}" if listed else "load a model into the server"
        return Check(_NAME, Status.FAIL, f"{root}: reachable, but model {model!r} is not "
                     f"listed (it lists: {shown or 'nothing'})", fix)
    return Check(_NAME, Status.OK, f"{root}: reachable, model {model!r} listed "
                 f"({len(listed)} model{'s' if len(listed) != 1 else ''})")


def _without_password(url: str) -> str:
    """``url`` as the report may show it: a password in it is replaced by ``***``."""
    try:
        parsed = httpx.URL(url)
    except (httpx.InvalidURL, TypeError, ValueError):
        return url
    return str(parsed.copy_with(username=parsed.username, password="***")) \
        if parsed.password else url


def check_auto(base_url: str | None, model: str | None) -> Check:
    """What ``--llm auto`` would use here: a warning when it is the small embedded model,
    a failure when nothing is found."""
    name = "llm auto"
    try:
        choice = choose(model, base_url)
    except LLMUnavailable as exc:
        return Check(name, Status.FAIL, one_line(str(exc))[:400],
                     "ollama serve (or llama-server, or vLLM), or pass --base-url URL")
    used = f"{choice.backend}" + (f" {choice.model}" if choice.model else "") + \
        (f" at {choice.base_url}" if choice.base_url else "")
    if choice.weak:
        return Check(name, Status.WARN, "would use the embedded SmolLM2-135M: no local "
                     "server answered (a small model for offline smoke runs)",
                     "start Ollama, llama.cpp's llama-server or vLLM on 127.0.0.1, or pass "
                     "--base-url URL")
    return Check(name, Status.OK, f"would use {used} ({choice.why})")
