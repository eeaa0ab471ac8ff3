"""The service's HTTP guard rails: refusals as one-line JSON, the bearer token, the body
limit on the bytes actually read and on how deep its JSON nests, security headers, and the
lock that keeps one server per database."""

from __future__ import annotations

import secrets
from pathlib import Path
from urllib.parse import parse_qs

from fastapi.responses import JSONResponse, RedirectResponse
from starlette.datastructures import MutableHeaders
from starlette.requests import cookie_parser
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from llm_grop import locking
from llm_grop.service.config import is_loopback
from llm_grop.web import GONE, TOO_LARGE, is_json, json_problem, read_body, replaying

#: The cookie a browser keeps the server's token in, after opening ``/?token=...`` once.
TOKEN_COOKIE = "llm_grop_token"
#: Each status's code; a refusal may name a more precise one (``bad_host``, ``bad_json``).
CODES = {400: "bad_input", 401: "unauthorized", 403: "forbidden", 404: "not_found",
         405: "method_not_allowed", 409: "infeasible", 413: "too_large",
         415: "not_json", 416: "bad_range", 422: "bad_input", 429: "overloaded",
         500: "internal", 503: "llm_unavailable", 504: "timeout"}
SECURITY_HEADERS = {
    "Content-Security-Policy": "default-src 'self'; img-src 'self'; media-src 'self'; "
                               "script-src 'self'; style-src 'self'; frame-ancestors 'none'; "
                               "form-action 'self'",
    "X-Content-Type-Options": "nosniff",
    # same-origin, not no-referrer: under no-referrer a browser posts forms with "Origin:
    # null", and the playground could not tell its own forms from another site's.
    "Referrer-Policy": "same-origin",
    "X-Frame-Options": "DENY",
}


class Refused(Exception):
    """A refusal: its HTTP status, one line, and headers (``Retry-After``)."""

    def __init__(self, status: int, message: str, headers: dict[str, str] | None = None):
        super().__init__(message)
        self.status, self.message, self.headers = status, message, headers or {}


def error_response(status: int, message: str, headers: dict[str, str] | None = None,
                   code: str | None = None) -> JSONResponse:
    """``{"error": message, "code": ...}`` with ``status``; the code is the status's
    unless given."""
    return JSONResponse({"error": message, "code": code or CODES.get(status, "bad_input")},
                        status_code=status, headers=headers)


class Guard:
    """ASGI middleware in front of everything: the bearer token (or, for a browser, the
    token cookie on reads and on the playground's forms), the body limit on the bytes
    actually read (chunked or not), JSON bodies the app can read (UTF-8, JSON, nested at
    most ``max_depth`` deep: 422 ``bad_json`` otherwise), and security headers on every
    answer."""

    def __init__(self, app: ASGIApp, *, token: str | None, max_body: int,
                 max_depth: int) -> None:
        self.app, self.token = app, token
        self.max_body, self.max_depth = max_body, max_depth

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = MutableHeaders(scope=message)
                for key, value in SECURITY_HEADERS.items():
                    headers.setdefault(key, value)
            await send(message)

        headers = dict(scope["headers"])
        if self.token is None and not is_loopback(_host(headers)):
            # Without a token only this machine may call: a page elsewhere that renamed
            # itself to 127.0.0.1 (DNS rebinding) still sends its own name as Host. An
            # address in Host is no such name, and a loopback one is this machine.
            await error_response(400, "host: this server answers only to 127.0.0.1 (or "
                                      "another loopback address), localhost or [::1]; "
                                      "serve other hosts with --token", code="bad_host"
                                 )(scope, receive, with_headers)
            return
        if self.token is not None and not self._allowed(scope, headers):
            answer = self._login(scope) or error_response(
                401, "missing or wrong token: send 'Authorization: Bearer <token>'",
                {"WWW-Authenticate": "Bearer"})
            await answer(scope, receive, with_headers)
            return
        api_post = scope["method"] == "POST" and scope["path"].startswith("/v1/")
        content_type = headers.get(b"content-type")
        if api_post and not is_json(content_type):
            given = repr(content_type.decode("latin-1")[:60]) if content_type else "none"
            await error_response(415, f"content-type: send the body as application/json, "
                                      f"got {given}")(scope, receive, with_headers)
            return
        body = await read_body(receive, self.max_body, headers.get(b"content-length"))
        if body is GONE:
            return
        if body is TOO_LARGE:
            # The rest of the body may still be on its way: this connection is done.
            await error_response(413, f"request body larger than this server's "
                                      f"{self.max_body} bytes", {"Connection": "close"}
                                 )(scope, receive, with_headers)
            return
        assert isinstance(body, bytes)
        problem = json_problem(body, self.max_depth) if api_post and body else None
        if problem is not None:
            await error_response(422, problem, code="bad_json")(scope, receive, with_headers)
            return
        await self.app(scope, replaying(body, receive), with_headers)

    def _allowed(self, scope: Scope, headers: dict[bytes, bytes]) -> bool:
        assert self.token is not None
        scheme, _, value = headers.get(b"authorization", b"").decode("latin-1").partition(" ")
        if scheme.lower() == "bearer" and _same(value.strip(), self.token):
            return True
        # A browser has no header to send: the cookie counts for reads, and for the
        # playground's forms (which check the Origin themselves), never for the JSON API.
        page = scope["method"] in ("GET", "HEAD") or not scope["path"].startswith("/v1/")
        return page and _same(_cookie(headers, TOKEN_COOKIE), self.token)

    def _login(self, scope: Scope) -> RedirectResponse | None:
        """``GET /?token=...`` with the right token: the cookie set, back to the page."""
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        given = (query.get("token") or [""])[0]
        if scope["path"] != "/" or not _same(given, self.token or ""):
            return None
        answer = RedirectResponse("/", status_code=303)
        # Lax, so that a permalink opened from mail or chat arrives with it; the forms
        # check their Origin, and the JSON API never takes the cookie.
        answer.set_cookie(TOKEN_COOKIE, given, httponly=True, samesite="lax", path="/",
                          secure=scope.get("scheme") == "https")
        return answer


def _same(given: str, token: str) -> bool:
    return bool(given) and secrets.compare_digest(given.encode(), token.encode())


def _cookie(headers: dict[bytes, bytes], name: str) -> str:
    return cookie_parser(headers.get(b"cookie", b"").decode("latin-1")).get(name, "")


def _host(headers: dict[bytes, bytes]) -> str:
    """The Host header's name, without its port."""
    host = headers.get(b"host", b"").decode("latin-1").lower()
    if host.startswith("["):
        return host.partition("]")[0] + "]"
    return host.rpartition(":")[0] if host.count(":") == 1 else host


def hold_lock(db: Path) -> int:
    """Take the database's lock file, so that one server at a time owns its jobs; the file
    descriptor that holds it (:mod:`llm_grop.locking`)."""
    return locking.hold(db.with_name(db.name + ".lock"), "db", db,
                        "another llm-grop serve")
