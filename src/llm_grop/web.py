"""What llm-grop's two websites (the rating study, the service) share: reading a request
body up to a limit on the bytes actually received, chunked or not; telling a JSON body from
others and refusing one that cannot be read, or is nested too deep, before it is parsed for
the app; checking that a form was posted from the site itself; and serving over uvicorn
with deadlines on reading each request, so that a client that stalls is closed.

This module imports nothing from the package but its errors, so both may use it.
"""

from __future__ import annotations

import asyncio
import email.message
import json
import re
import socket
import sys
from collections.abc import Awaitable, Callable
from http import HTTPStatus
from urllib.parse import urlsplit

from starlette.types import ASGIApp, Message, Receive

from llm_grop.errors import BadInput

#: What :func:`read_body` found: the body, or that it was too large or the client left.
TOO_LARGE = object()
GONE = object()
#: The most bytes a request's line and headers may take before they end (431 beyond).
MAX_HEADER_BYTES = 64 * 1024


async def read_body(receive: Receive, limit: int, declared: bytes | None) -> bytes | object:
    """The request body, read whole, or :data:`TOO_LARGE` as soon as the declared length
    (``Content-Length``) or the bytes received exceed ``limit``, or :data:`GONE` if the
    client disconnected. A chunked body that never ends costs no more than ``limit``."""
    if declared is not None and (not declared.isdigit() or int(declared) > limit):
        return TOO_LARGE
    chunks, size, more = [], 0, True
    while more:
        message = await receive()
        if message["type"] == "http.disconnect":
            return GONE
        chunk = message.get("body", b"")
        size += len(chunk)
        if size > limit:
            return TOO_LARGE
        chunks.append(chunk)
        more = message.get("more_body", False)
    return b"".join(chunks)


def replaying(body: bytes, receive: Receive) -> Callable[[], Awaitable[Message]]:
    """A ``receive`` that hands the app ``body`` (already read) once, then the client's
    own messages (a disconnect)."""
    sent = False

    async def replay() -> Message:
        nonlocal sent
        if not sent:
            sent = True
            return {"type": "http.request", "body": body, "more_body": False}
        return await receive()

    return replay


def is_json(content_type: bytes | None) -> bool:
    """Whether a body of this ``Content-Type`` is JSON to FastAPI: ``application/json``
    or ``application/*+json``, parameters aside, in any case."""
    if not content_type:
        return False
    message = email.message.Message()
    message["content-type"] = content_type.decode("latin-1")
    subtype = message.get_content_subtype()
    return message.get_content_maintype() == "application" and (
        subtype == "json" or subtype.endswith("+json"))


def json_problem(body: bytes, max_depth: int) -> str | None:
    """What makes ``body`` unreadable as JSON, in one line, or ``None`` when it reads:
    parsed exactly as the app will parse it (``json.loads`` on the bytes), and refused
    when its arrays and objects nest more than ``max_depth`` deep (pydantic breaks on
    values a few hundred deep)."""
    try:
        json.loads(body)
    except UnicodeDecodeError as exc:
        return f"body: not UTF-8 text ({exc.reason} at byte {exc.start})"
    except json.JSONDecodeError as exc:
        return f"body: not JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})"
    except RecursionError:
        return _too_deep(max_depth)
    except ValueError as exc:
        if "digits" not in str(exc):
            return f"body: not JSON ({exc})"
        digits = sys.get_int_max_str_digits()  # an integer beyond Python's conversion limit
        return f"body: a number of more than {digits} digits; this server reads at most {digits}"
    # Brackets inside strings count here too: only a cheap bound, before the walk.
    if body.count(b"[") + body.count(b"{") > max_depth and _deeper(body, max_depth):
        return _too_deep(max_depth)
    return None


def _too_deep(max_depth: int) -> str:
    return (f"body: arrays and objects nested more than {max_depth} deep; this server reads "
            f"at most {max_depth} levels")


def _deeper(body: bytes, limit: int) -> bool:
    """Whether the arrays and objects of ``body`` (JSON that parses) nest more than
    ``limit`` deep, the body itself being level 1. Its brackets outside strings, as one
    kind, lose their innermost level with each pass of ``bytes.replace``: as many passes
    as the nesting is deep, each at C speed (a walk over the parsed value in Python took
    over 100 ms for a body of 60,000 small arrays, on the server's event loop)."""
    skeleton = _STRING.sub(b"", body).translate(_AS_SQUARE, _NOT_BRACKET)
    for _ in range(limit):
        if not skeleton:
            return False
        skeleton = skeleton.replace(b"[]", b"")
    return bool(skeleton)


#: A JSON string, escapes and all; ``{`` and ``}`` as ``[`` and ``]``; every other byte.
_STRING = re.compile(rb'"[^"\\]*(?:\\.[^"\\]*)*"', re.DOTALL)
_AS_SQUARE = bytes.maketrans(b"{}", b"[]")
_NOT_BRACKET = bytes(b for b in range(256) if b not in b"[]{}")


def same_origin(origin: str | None, host: str | None) -> bool:
    """Whether a form's ``Origin`` header names the site it was posted to (``Host``). A
    missing or ``null`` Origin is not: browsers send one with every form they post, so
    its absence means something else made the request."""
    if not origin or origin == "null" or not host:
        return False
    return urlsplit(origin).netloc.lower() == host.lower()


def listen(host: str, port: int) -> socket.socket:
    """A socket listening on ``host`` (a name or an address, IPv4 preferred) and ``port``
    (0: any free one); :class:`BadInput` naming the flags when it cannot be had."""
    sock = None
    try:
        found = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM,
                                   flags=socket.AI_PASSIVE)
        family, kind, proto, _, address = min(found, key=lambda f: f[0] != socket.AF_INET)
        sock = socket.socket(family, kind, proto)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
        sock.listen(2048)
        return sock
    except OSError as exc:
        if sock is not None:
            sock.close()
        raise BadInput(f"--host {host} --port {port}: cannot listen "
                       f"({exc.strerror or exc})") from None


def url_of(sock: socket.socket) -> str:
    """The ``http://`` URL of a listening socket's address and port."""
    address, port = sock.getsockname()[:2]
    return f"http://[{address}]:{port}/" if ":" in address else f"http://{address}:{port}/"


def run(app: ASGIApp, sock: socket.socket, *, header_timeout_s: float,
        body_timeout_s: float, forwarded_allow_ips: str | None = None,
        graceful_s: float | None = None) -> bool:
    """Serve ``app`` on ``sock`` with uvicorn, with the deadlines of
    :func:`deadline_protocol`, until a signal stops it (uvicorn shuts down gracefully,
    then raises the signal again); whether it had started (its lifespan ran).
    ``X-Forwarded-For`` and ``-Proto`` are read only from the proxies
    ``forwarded_allow_ips`` names (comma-separated, or ``*``); with none, a client is its
    own address and cannot claim another."""
    import uvicorn

    config = uvicorn.Config(app, log_level="warning", access_log=False,
                            http=deadline_protocol(header_timeout_s, body_timeout_s),
                            proxy_headers=bool(forwarded_allow_ips),
                            forwarded_allow_ips=forwarded_allow_ips or None,
                            timeout_graceful_shutdown=graceful_s)
    server = uvicorn.Server(config)
    server.run(sockets=[sock])
    return server.started


def deadline_protocol(header_timeout_s: float, body_timeout_s: float) -> type[asyncio.Protocol]:
    """uvicorn's HTTP/1.1 protocol (httptools) with deadlines on reading a request.

    A connection that has not sent a request's line and headers within
    ``header_timeout_s`` seconds (of connecting, or of the request's first byte), or its
    body within ``body_timeout_s`` seconds of its headers, is closed: with a 408 if the
    request had begun and nothing was being answered, silently otherwise. Headers longer
    than :data:`MAX_HEADER_BYTES` are answered 431 and the connection closed. uvicorn by
    itself only closes connections idle between requests (``timeout_keep_alive``), and
    would hold one that sent half a request for ever.
    """
    from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol

    class Deadlines(HttpToolsProtocol):  # type: ignore[misc]
        _timer: asyncio.TimerHandle | None = None
        #: Reading a request's line and headers, or waiting for the next request's.
        _heading = True
        #: A byte of the request being read has arrived.
        _begun = False
        _header_bytes = 0

        def connection_made(self, transport: asyncio.BaseTransport) -> None:
            super().connection_made(transport)
            self._arm(header_timeout_s, "headers")

        def connection_lost(self, exc: Exception | None) -> None:
            self._disarm()
            super().connection_lost(exc)

        def data_received(self, data: bytes) -> None:
            if self._heading:
                self._header_bytes += len(data)
            super().data_received(data)
            if self._heading and self._header_bytes > MAX_HEADER_BYTES:
                self._refuse(431, f"headers: more than {MAX_HEADER_BYTES} bytes; this server "
                                  f"reads at most {MAX_HEADER_BYTES}", "too_large")

        def on_message_begin(self) -> None:
            super().on_message_begin()
            self._begun = True
            if self._timer is None:
                self._arm(header_timeout_s, "headers")

        def on_headers_complete(self) -> None:
            self._disarm()
            self._heading, self._header_bytes = False, 0
            super().on_headers_complete()
            self._arm(body_timeout_s, "body")

        def on_message_complete(self) -> None:
            self._disarm()
            self._heading, self._begun = True, False
            super().on_message_complete()

        def _arm(self, seconds: float, part: str) -> None:
            self._disarm()
            self._timer = self.loop.call_later(seconds, self._expire, seconds, part)

        def _disarm(self) -> None:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None

        def _expire(self, seconds: float, part: str) -> None:
            self._timer = None
            if self.transport.is_closing():
                return
            cycle = self.cycle
            if self.pipeline or (part == "headers" and cycle is not None
                                 and not cycle.response_complete):
                # An earlier request on this connection is still being answered: the
                # wait is the server's, not the client's.
                self._arm(seconds, part)
            elif (part == "headers" and not self._begun) or (
                    part == "body" and cycle is not None and cycle.response_started):
                self.transport.close()  # nothing begun to answer, or answered already
            else:
                self._refuse(408, f"{part}: not received within {seconds:g} s; the "
                                  "connection is closed", "timeout")

        def _refuse(self, status: int, message: str, code: str) -> None:
            if self.transport.is_closing():
                return
            body = json.dumps({"error": message, "code": code}).encode()
            head = (f"HTTP/1.1 {status} {HTTPStatus(status).phrase}\r\n"
                    f"content-type: application/json\r\ncontent-length: {len(body)}\r\n"
                    "connection: close\r\n\r\n")
            self.transport.write(head.encode("ascii") + body)
            self.transport.close()

    return Deadlines
