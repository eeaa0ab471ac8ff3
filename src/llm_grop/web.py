"""What llm-grop's two websites (the rating study, the service) share: reading a request
body up to a limit on the bytes actually received, chunked or not, and checking that a
form was posted from the site itself.

This module imports nothing from the package but its errors, so both may use it.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from urllib.parse import urlsplit

from starlette.types import Message, Receive

#: What :func:`read_body` found: the body, or that it was too large or the client left.
TOO_LARGE = object()
GONE = object()


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


def same_origin(origin: str | None, host: str | None) -> bool:
    """Whether a form's ``Origin`` header names the site it was posted to (``Host``). A
    missing or ``null`` Origin is not: browsers send one with every form they post, so
    its absence means something else made the request."""
    if not origin or origin == "null" or not host:
        return False
    return urlsplit(origin).netloc.lower() == host.lower()
