"""The service's answer while its disk refuses writes (:mod:`.storage`): 503 with
``Retry-After`` and ``{"error": one line, "code": "storage_full"}`` (or
``"storage_read_only"``), instead of an internal error; a playground page says the same."""

from __future__ import annotations

import sqlite3
from collections.abc import Awaitable, Callable

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse, Response
from starlette.concurrency import run_in_threadpool

from llm_grop.service.service import Service
from llm_grop.service.storage import CODES, MESSAGES, RETRY_AFTER_S, Unwritable, problem

Handler = Callable[[Request, Exception], Awaitable[Response]]


def answer_storage_errors(app: FastAPI, service: Service, internal: Handler) -> None:
    """Answer the disk's refusals on ``app`` with 503 (logged once per episode); any other
    database or OS error goes to ``internal``. Handled here, below the server's own error
    middleware, an answered refusal prints no traceback."""

    async def storage(request: Request, exc: Exception) -> Response:
        found = problem(exc, service.config.db.parent)
        if found is None:
            return await internal(request, exc)
        service.storage.trouble(found)
        headers = {"Retry-After": str(RETRY_AFTER_S)}
        page = getattr(app.state, "page_error", None)
        if page is not None and not request.url.path.startswith("/v1/"):
            html: Response = await run_in_threadpool(page, request, 503, MESSAGES[found])
            html.headers.update(headers)
            return html
        return JSONResponse({"error": MESSAGES[found], "code": CODES[found]},
                            status_code=503, headers=headers)

    for kind in (Unwritable, sqlite3.Error, OSError):
        app.add_exception_handler(kind, storage)  # type: ignore[arg-type]
