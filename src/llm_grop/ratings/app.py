"""The rating website: FastAPI pages and a JSON API over one study database.

Raters join with an invite code, which sets a session cookie (HttpOnly, SameSite=Strict,
Secure over HTTPS) and gives a CSRF token that every write must carry: as the
``X-CSRF-Token`` header on the API, as a hidden field in the pages' forms. The pages are
rendered on the server; ``static/rate.js`` only turns key presses and clicks into API
calls. Every refusal of the API is a 4xx status with ``{"error": "one line"}``. Admin
endpoints need ``Authorization: Bearer <admin token>``.
"""

from __future__ import annotations

import contextlib
import math
import secrets
import time
from collections import OrderedDict, deque
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Annotated, Any

from fastapi import Depends, FastAPI, Form, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse, RedirectResponse, Response
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, ConfigDict, Field, StrictInt, StrictStr
from starlette.datastructures import MutableHeaders
from starlette.exceptions import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from llm_grop.datafile import problem_line
from llm_grop.ratings.db import connect
from llm_grop.ratings.pages import STATIC, render
from llm_grop.ratings.store import (
    SESSION_TTL_S,
    RatingStore,
    Refused,
    Session,
    export_csv,
    image_url,
)
from llm_grop.web import (
    GONE,
    TOO_LARGE,
    is_json,
    json_problem,
    read_body,
    replaying,
    same_origin,
)

COOKIE = "llm_grop_session"
CSRF_HEADER = "X-CSRF-Token"
#: Failed join attempts one client address may make in a minute.
JOINS_PER_MINUTE = 10
#: Addresses whose failed joins are remembered at once; the longest idle are forgotten.
MAX_ADDRESSES = 10_000
#: The largest request body accepted, bytes: a rating or a join is a few dozen.
MAX_BODY_BYTES = 16 * 1024
#: How deep a JSON body's arrays and objects may nest: a rating or a join is one object.
MAX_BODY_DEPTH = 8
#: Headers on every answer: no framing, no sniffing, no referrer, nothing from elsewhere.
SECURITY_HEADERS = {
    "Content-Security-Policy": "default-src 'self'; img-src 'self'; script-src 'self'; "
                               "style-src 'self'; frame-ancestors 'none'; form-action 'self'",
    "X-Content-Type-Options": "nosniff",
    # same-origin, not no-referrer: under no-referrer a browser posts forms with "Origin:
    # null", and the site could not tell its own forms from another site's.
    "Referrer-Policy": "same-origin",
    "X-Frame-Options": "DENY",
}


class Hardening:
    """ASGI middleware: :data:`SECURITY_HEADERS` on every answer, ``no-store`` on pages and
    the API (whose answers are a rater's own), 413 for a body larger than
    :data:`MAX_BODY_BYTES`, declared or as read (a chunked body is read no further), and
    422 for a JSON body that cannot be read (not UTF-8, not JSON, nested deeper than
    :data:`MAX_BODY_DEPTH`)."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        static = scope["path"].startswith("/static/")

        async def with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = MutableHeaders(scope=message)
                for key, value in SECURITY_HEADERS.items():
                    headers[key] = value
                if not static and "cache-control" not in headers:
                    headers["Cache-Control"] = "no-store"
            await send(message)

        headers = dict(scope["headers"])
        body = await read_body(receive, MAX_BODY_BYTES, headers.get(b"content-length"))
        if body is GONE:
            return
        if body is TOO_LARGE:
            # The rest of the body may still be on its way: this connection is done.
            too_big = JSONResponse({"error": f"request body larger than {MAX_BODY_BYTES} "
                                             "bytes"}, status_code=413,
                                   headers={"Connection": "close"})
            await too_big(scope, receive, with_headers)
            return
        assert isinstance(body, bytes)
        # Older FastAPI reads a body without a Content-Type as JSON too.
        kind = headers.get(b"content-type")
        problem = json_problem(body, MAX_BODY_DEPTH) if body and scope["path"].startswith(
            "/api/") and (kind is None or is_json(kind)) else None
        if problem is not None:
            await JSONResponse({"error": problem}, status_code=422)(scope, receive,
                                                                     with_headers)
            return
        await self.app(scope, replaying(body, receive), with_headers)


class JoinLimit:
    """At most :data:`JOINS_PER_MINUTE` failed join attempts (unknown codes) per client
    address in any minute, so invite codes cannot be guessed quickly, while a class
    joining from behind one address is never held back; more are refused with 429 and
    ``Retry-After``."""

    def __init__(self, per_minute: int = JOINS_PER_MINUTE) -> None:
        self.per_minute = per_minute
        self.seen: OrderedDict[str, deque[float]] = OrderedDict()

    def join(self, request: Request, rs: RatingStore, code: str) -> Session:
        """``rs.join(code)`` for ``request``'s address, refused while it has failed too
        often; a failure is counted."""
        now = time.monotonic()
        address = request.client.host if request.client is not None else "?"
        recent = self.seen.get(address, deque())
        while recent and now - recent[0] >= 60:
            recent.popleft()
        if len(recent) >= self.per_minute:
            wait = max(1, math.ceil(60 - (now - recent[0])))
            raise Refused(429, f"too many failed join attempts from this address; try "
                               f"again in {wait} s", headers={"Retry-After": str(wait)})
        try:
            return rs.join(code)
        except Refused:
            recent.append(now)
            self.seen[address] = recent
            self.seen.move_to_end(address)
            while len(self.seen) > MAX_ADDRESSES:  # the longest idle go first
                self.seen.popitem(last=False)
            raise


class JoinBody(BaseModel):
    """``POST /api/session``."""

    model_config = ConfigDict(extra="forbid")
    code: StrictStr = Field(max_length=100)


class RatingBody(BaseModel):
    """``POST /api/ratings``: the rater comes from the session, never from the body."""

    model_config = ConfigDict(extra="forbid")
    item: StrictStr = Field(max_length=100)
    rating: StrictInt = Field(ge=1, le=5)


async def _store(request: Request) -> RatingStore:
    """The app's store. Every endpoint is a coroutine on the server's one event loop, so
    one connection serves them all in turn, with no thread hops; SQLite answers each in
    well under a millisecond."""
    return request.app.state.store


Store = Annotated[RatingStore, Depends(_store)]


def create_app(db: Path, *, admin_token: str, ttl_s: float = SESSION_TTL_S) -> FastAPI:
    """The website for the study in ``db``; admin endpoints take ``admin_token``."""
    conn = connect(db)  # refuses a missing or foreign file now, and migrates it

    @contextlib.asynccontextmanager
    async def lifespan(_: FastAPI) -> AsyncIterator[None]:
        try:
            yield
        finally:
            conn.close()

    app = FastAPI(title="llm-grop ratings", docs_url=None, redoc_url=None, openapi_url=None,
                  lifespan=lifespan)
    app.mount("/static", StaticFiles(directory=STATIC), name="static")
    app.state.store = RatingStore(conn, ttl_s=ttl_s)
    app.add_middleware(Hardening)

    @app.exception_handler(Refused)
    async def refused(request: Request, exc: Refused) -> Response:
        if _is_api(request):
            return JSONResponse({"error": exc.message}, status_code=exc.status,
                                headers=exc.headers)
        if exc.status == 401:
            return HTMLResponse(render("join.html", error=exc.message), status_code=401)
        return HTMLResponse(render("error.html", error=exc.message), status_code=exc.status,
                            headers=exc.headers)

    @app.exception_handler(RequestValidationError)
    async def invalid(request: Request, exc: RequestValidationError) -> Response:
        return await refused(request, Refused(422, problem_line(exc.errors(), exc.body)))

    @app.exception_handler(HTTPException)
    async def http_error(request: Request, exc: HTTPException) -> Response:
        return await refused(request, Refused(exc.status_code, str(exc.detail)))

    # ---- the JSON API -------------------------------------------------------------------

    joins = JoinLimit()

    @app.post("/api/session")
    async def api_join(body: JoinBody, request: Request, rs: Store) -> Response:
        session = joins.join(request, rs, body.code)
        done, total = rs.progress(session.rater_id)
        response = JSONResponse({"rater": session.rater, "csrf": session.csrf, "done": done,
                                 "total": total, "expires_at": session.expires_at})
        _set_cookie(response, request, session, ttl_s)
        return response

    @app.delete("/api/session")
    async def api_leave(request: Request, rs: Store) -> Response:
        _check_csrf(_session(request, rs), request.headers.get(CSRF_HEADER))
        rs.end(request.cookies[COOKIE])
        response = JSONResponse({"left": True})
        response.delete_cookie(COOKIE, path="/")
        return response

    @app.get("/api/next")
    async def api_next(request: Request, rs: Store) -> dict[str, Any]:
        return rs.next_item(_session(request, rs).rater_id).to_json()

    @app.post("/api/ratings", status_code=201)
    async def api_rate(body: RatingBody, request: Request, rs: Store) -> dict[str, Any]:
        session = _session(request, rs)
        _check_csrf(session, request.headers.get(CSRF_HEADER))
        done, total = rs.rate(session.rater_id, body.item, body.rating)
        return {"item": body.item, "rating": body.rating, "done": done, "total": total}

    @app.get("/api/admin/progress")
    async def api_progress(request: Request, rs: Store) -> dict[str, Any]:
        _check_admin(request, admin_token)
        return rs.admin_progress()

    @app.get("/api/admin/export.csv")
    async def api_export(request: Request, rs: Store) -> Response:
        _check_admin(request, admin_token)
        return Response(export_csv(rs.export_rows()), media_type="text/csv",
                        headers={"Content-Disposition": 'attachment; filename="ratings.csv"'})

    @app.get("/images/{item}")
    async def picture(item: str, request: Request, rs: Store) -> Response:
        data = rs.picture(_session(request, rs).rater_id, item)
        return Response(data, media_type="image/png",
                        headers={"Cache-Control": "private, max-age=3600"})

    # ---- the pages ----------------------------------------------------------------------

    @app.get("/", response_class=HTMLResponse)
    async def join_page() -> str:
        return render("join.html")

    @app.post("/join")
    async def join_form(code: Annotated[str, Form(max_length=100)], request: Request,
                  rs: Store) -> Response:
        _check_origin(request)
        session = joins.join(request, rs, code)
        response = RedirectResponse("/guidelines", status_code=303)
        _set_cookie(response, request, session, ttl_s)
        return response

    @app.get("/guidelines", response_class=HTMLResponse)
    async def guidelines_page(request: Request, rs: Store) -> str:
        session = _session(request, rs)
        done, total = rs.progress(session.rater_id)
        return render("guidelines.html", csrf=session.csrf, rater=session.rater, done=done,
                      total=total)

    @app.get("/rate", response_class=HTMLResponse)
    async def rate_page(request: Request, rs: Store) -> str:
        session = _session(request, rs)
        nxt = rs.next_item(session.rater_id)
        return render("rate.html", csrf=session.csrf, rater=session.rater, next=nxt,
                      image=image_url(nxt.item) if nxt.item else None)

    @app.post("/rate")
    async def rate_form(item: Annotated[str, Form(max_length=100)],
                  rating: Annotated[str, Form(max_length=10)],
                  csrf: Annotated[str, Form(max_length=100)], request: Request,
                  rs: Store) -> Response:
        _check_origin(request)
        session = _session(request, rs)
        _check_csrf(session, csrf)
        value: object = int(rating) if rating.isdigit() and rating.isascii() else rating
        rs.rate(session.rater_id, item, value)
        return RedirectResponse("/rate", status_code=303)

    @app.post("/leave")
    async def leave_form(csrf: Annotated[str, Form(max_length=100)], request: Request,
                   rs: Store) -> Response:
        _check_origin(request)
        _check_csrf(_session(request, rs), csrf)
        rs.end(request.cookies[COOKIE])
        response = RedirectResponse("/", status_code=303)
        response.delete_cookie(COOKIE, path="/")
        return response

    return app


def _is_api(request: Request) -> bool:
    return request.url.path.startswith(("/api/", "/images/"))


def _session(request: Request, rs: RatingStore) -> Session:
    return rs.session(request.cookies.get(COOKIE))


def _check_csrf(session: Session, token: str | None) -> None:
    if not token or not secrets.compare_digest(token.encode(), session.csrf.encode()):
        raise Refused(403, f"missing or wrong CSRF token (send the session's token as "
                           f"{CSRF_HEADER})")


def _check_origin(request: Request) -> None:
    """Refuse a form posted from another site, or without an Origin to tell (a login
    CSRF needs no token: the join form has none yet)."""
    if not same_origin(request.headers.get("origin"), request.headers.get("host")):
        raise Refused(403, "form posted from another site (or without an Origin header)")


def _check_admin(request: Request, token: str) -> None:
    given = request.headers.get("authorization", "")
    scheme, _, value = given.partition(" ")
    if scheme.lower() != "bearer" or not secrets.compare_digest(value.strip().encode(),
                                                                 token.encode()):
        raise Refused(401, "admin endpoints need 'Authorization: Bearer <admin token>'")


def _set_cookie(response: Response, request: Request, session: Session, ttl_s: float) -> None:
    response.set_cookie(COOKIE, session.token, max_age=int(ttl_s), path="/", httponly=True,
                        samesite="strict", secure=request.url.scheme == "https")
