"""What the openai backend reads off the wire, apart from the backend itself: the HTTP
client's errors, a ``Retry-After`` header in seconds, one-line texts of a server's errors,
and :class:`Cutoff`, which ends an attempt at its deadline whatever the server sends."""

from __future__ import annotations

import contextlib
import datetime
import email.utils
import math
import re
import socket
import threading
import time
from types import ModuleType

import httpx
import openai

#: Longest server error text quoted in an error message, in characters.
MAX_DETAIL = 200

_ERRNO_PREFIX = re.compile(r"^\[Errno -?\d+\]\s*")



def _http_modules() -> tuple[ModuleType, ...]:
    """The HTTP client libraries the SDK may speak through: httpx, and httpx2 (a fork
    with its own exception classes) that newer ``openai`` releases use."""
    try:
        import httpx2
    except ImportError:
        return (httpx,)
    return (httpx, httpx2)


#: A timeout, and any failure, of the HTTP client while an answer is read.
TIMEOUTS: tuple[type[Exception], ...] = tuple(m.TimeoutException for m in _http_modules())
HTTP_ERRORS: tuple[type[Exception], ...] = tuple(m.HTTPError for m in _http_modules())


def retry_after_s(value: str | None, scale: float) -> float | None:
    """A Retry-After value in seconds: a number (times ``scale``) or an HTTP date (UTC if
    it names no zone); ``None`` for anything else, which is ignored."""
    if not value:
        return None
    try:
        wait = float(value) * scale
    except ValueError:
        try:
            when = email.utils.parsedate_to_datetime(value)
        except (TypeError, ValueError, IndexError):
            return None
        if when.tzinfo is None:
            when = when.replace(tzinfo=datetime.UTC)
        wait = when.timestamp() - time.time()
    return max(wait, 0.0) if math.isfinite(wait) else None


class Cutoff:
    """One attempt's socket and whether its deadline passed: :meth:`cut`, called at the
    deadline from a timer's thread, shuts the socket down so that a read blocked on it
    ends, whatever the server is sending."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._sock: socket.socket | None = None
        self.fired = False

    def watch(self, sock: socket.socket | None) -> None:
        """The attempt's socket, once connected (shut at once if the deadline passed)."""
        with self._lock:
            self._sock = sock
            if self.fired:
                _shut(sock)

    def cut(self) -> None:
        """The deadline passed."""
        with self._lock:
            self.fired = True
            _shut(self._sock)


def _shut(sock: socket.socket | None) -> None:
    if sock is not None:
        with contextlib.suppress(OSError):
            sock.shutdown(socket.SHUT_RDWR)


def root_cause(exc: BaseException) -> str:
    """The innermost cause's message, e.g. ``connection refused``."""
    inner: BaseException = exc
    for _ in range(20):
        nxt = inner.__cause__ or inner.__context__
        if nxt is None:
            break
        inner = nxt
    text = _ERRNO_PREFIX.sub("", one_line(inner)) or type(inner).__name__
    return text[:1].lower() + text[1:]


def detail(exc: openai.APIStatusError) -> str:
    """The server's own error message, shortened to one line."""
    body = exc.body
    message: object = None
    if isinstance(body, dict):
        # The SDK hands over the "error" object of {"error": {"message": ...}} bodies.
        inner = body.get("error", body)
        message = inner.get("message") if isinstance(inner, dict) else inner
    if not isinstance(message, str) or not message.strip():
        message = exc.message
    return one_line(str(message))


def one_line(obj: object) -> str:
    text = " ".join(str(obj).split())
    return text if len(text) <= MAX_DETAIL else text[: MAX_DETAIL - 1] + "…"
