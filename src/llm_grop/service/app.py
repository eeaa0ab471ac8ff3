"""The service's FastAPI app: the versioned JSON API under ``/v1/``.

Every request is a job (:mod:`.jobs`). ``POST /v1/arrangements`` and ``POST /v1/plans``
answer when their job ends; ``POST /v1/runs`` answers at once with the job, which is
polled at ``GET /v1/runs/{id}`` or followed at ``GET /v1/runs/{id}/events``. Every
refusal is a 4xx with ``{"error": "one line", "code": ...}`` in the CLI's words: bad
input 422, nothing feasible 409, overload 429 with ``Retry-After``, a body too large 413,
a missing or wrong token 401.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import shutil
from collections.abc import AsyncIterator
from importlib import metadata
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response, StreamingResponse
from pydantic import BaseModel
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException

from llm_grop.errors import LLMGropError
from llm_grop.service.config import ServiceConfig
from llm_grop.service.http import Guard, Refused, error_response, hold_lock
from llm_grop.service.jobs import JobStore
from llm_grop.service.models import (
    ArrangeBody,
    ArrangementAnswer,
    ErrorAnswer,
    Info,
    JobAnswer,
    Pending,
    PlanAnswer,
    PlanBody,
    PreferencesAnswer,
    PreferencesBody,
    RunBody,
    one_line,
    preferences_answer,
)
from llm_grop.service.playground import add_playground
from llm_grop.service.service import Service, StillRunning
from llm_grop.service.storage_errors import answer_storage_errors
from llm_grop.service.workers import WorkerPool, status_of

log = logging.getLogger(__name__)

DESCRIPTION = (
    "Arrangements, task-motion plans and simulated runs of llm-grop (LLM-GROP, IROS 2023). "
    "Units are metres, radians and seconds; frames are the contract's (table frame: +x to "
    "the diner's right, +y away from the diner; room frame: the dining room's map). "
    "Every refusal is a 4xx with {\"error\": one line, \"code\": ...}: bad input 422, "
    "nothing feasible 409, overload 429 with Retry-After, too large 413, no token 401.")
#: Seconds between looks at a job whose events are streamed.
EVENTS_POLL_S = 0.2
_ERRORS: dict[int | str, dict[str, Any]] = {
    code: {"model": ErrorAnswer, "description": words} for code, words in (
        (401, "a missing or wrong bearer token"), (409, "nothing feasible"),
        (413, "the body is too large"), (422, "bad input"),
        (429, "the server is busy (see Retry-After)"),
        (503, "the server's LLM backend could not answer, or its disk is full or read-only "
              "(with Retry-After)"))} | {
    202: {"model": Pending, "description": "not ready within the server's wait; poll the "
                                           "permalink (also in Location)"}}


def create_app(config: ServiceConfig, *, workers: bool = True) -> FastAPI:
    """The service for ``config``; ``workers=False`` leaves the worker pool out (for
    publishing the OpenAPI document)."""
    lock = hold_lock(config.db) if workers else None
    try:
        store = JobStore(config.db) if workers else None
    except BaseException:
        if lock is not None:
            os.close(lock)
        raise
    if workers:
        shutil.rmtree(config.scratch, ignore_errors=True)
        config.scratch.mkdir(parents=True, exist_ok=True)
    pool = WorkerPool(config) if workers else None

    @contextlib.asynccontextmanager
    async def lifespan(_: FastAPI) -> AsyncIterator[None]:
        if store is not None and pool is not None:
            again = store.recover()
            if again:
                log.warning("%d job(s) left running by the last server were queued again",
                            again)
            pool.start()
        try:
            yield
        finally:
            if pool is not None:
                pool.stop()
            if store is not None:
                store.close()
            if lock is not None:
                os.close(lock)

    # The document's version is the API's (/v1/); GET /v1/info gives llm-grop's.
    app = FastAPI(title="llm-grop service", version="1", lifespan=lifespan,
                  docs_url=None, redoc_url=None, openapi_url="/v1/openapi.json",
                  description=DESCRIPTION)
    app.add_middleware(Guard, token=config.token, max_body=config.limits.body_bytes,
                       max_depth=config.limits.body_depth)

    @app.exception_handler(Refused)
    async def refused(request: Request, exc: Refused) -> Response:
        if not request.url.path.startswith("/v1/") and hasattr(app.state, "page_error"):
            return await run_in_threadpool(app.state.page_error, request, exc.status,
                                           exc.message)
        return error_response(exc.status, exc.message, exc.headers)

    @app.exception_handler(RequestValidationError)
    async def invalid(request: Request, exc: RequestValidationError) -> Response:
        model = _BODIES.get(request.url.path.rstrip("/"))
        return await refused(request, Refused(422, one_line(exc.errors(), exc.body, model)))

    @app.exception_handler(HTTPException)
    async def http_error(request: Request, exc: HTTPException) -> Response:
        return await refused(request, Refused(exc.status_code, str(exc.detail)))

    @app.exception_handler(LLMGropError)
    async def project_error(request: Request, exc: LLMGropError) -> Response:
        return await refused(request, Refused(*status_of(exc)))

    @app.exception_handler(StillRunning)
    async def still_running(_: Request, exc: StillRunning) -> Response:
        prefix = {"arrange": "/v1/arrangements/", "plan": "/v1/plans/",
                  "learn": "/v1/preferences/"}[exc.job.kind]
        link = prefix + exc.job.id
        return JSONResponse({"id": exc.job.id, "state": exc.job.state, "permalink": link},
                            status_code=202, headers={"Location": link})

    @app.exception_handler(Exception)
    async def internal(request: Request, exc: Exception) -> Response:
        log.error("internal error on %s", request.url.path, exc_info=exc)
        return await refused(request, Refused(500, f"internal error: {type(exc).__name__}"))

    service = Service(config, store)
    app.state.service = service
    answer_storage_errors(app, service, internal)

    def client(request: Request) -> str:
        return request.client.host if request.client is not None else "?"

    # Handlers that use the job store are plain functions, which the server runs in its
    # worker threads, or hand the store's calls to them: a store call may wait on a
    # worker's commit (a video), and must not stall every other request meanwhile.
    @app.get("/v1/info", response_model=Info, summary="What this server offers")
    def info() -> Info:
        from llm_grop.api import available_methods, available_simulators

        limits = config.limits
        return Info(version=_version(), backends=[b.name for b in config.backends],
                    methods=available_methods(), simulators=available_simulators(),
                    limits={"body_bytes": limits.body_bytes, "body_depth": limits.body_depth,
                            "request_chars": limits.request_chars,
                            "objects": limits.objects, "run_time_s": limits.run_time_s,
                            "queue": limits.queue,
                            "jobs_per_client": limits.jobs_per_client},
                    queue=service.jobs.counts())

    @app.post("/v1/arrangements", response_model=ArrangementAnswer, responses=_ERRORS,
              response_model_exclude_unset=True,
              summary="Arrange the objects of a request on a table")
    async def post_arrangement(body: ArrangeBody, request: Request) -> ArrangementAnswer:
        job_id = await run_in_threadpool(service.submit, "arrange", body, client(request))
        return service.arrangement(await service.finished(job_id))

    @app.get("/v1/arrangements/{job_id}", response_model=ArrangementAnswer,
             response_model_exclude_unset=True,
             responses=_ERRORS, summary="An arrangement at its permalink")
    async def get_arrangement(job_id: str) -> ArrangementAnswer:
        job = await run_in_threadpool(service.get, job_id, "arrange")
        return service.arrangement(await service.finished(job.id))

    @app.post("/v1/plans", response_model=PlanAnswer, responses=_ERRORS,
              response_model_exclude_unset=True,
              summary="A task-motion plan for a robot stack to execute")
    async def post_plan(body: PlanBody, request: Request) -> PlanAnswer:
        job_id = await run_in_threadpool(service.submit, "plan", body, client(request))
        return service.plan(await service.finished(job_id))

    @app.get("/v1/plans/{job_id}", response_model=PlanAnswer, responses=_ERRORS,
             response_model_exclude_unset=True,
             summary="A plan at its permalink")
    async def get_plan(job_id: str) -> PlanAnswer:
        job = await run_in_threadpool(service.get, job_id, "plan")
        return service.plan(await service.finished(job.id))

    @app.post("/v1/runs", response_model=JobAnswer, status_code=202, responses=_ERRORS,
              summary="Start a simulated run as a job")
    def post_run(body: RunBody, request: Request, response: Response) -> JobAnswer:
        job = service.get(service.submit("run", body, client(request)), "run")
        response.headers["Location"] = f"/v1/runs/{job.id}"
        return service.run(job)

    @app.get("/v1/runs/{job_id}", response_model=JobAnswer, responses=_ERRORS,
             summary="A run's state and result")
    def get_run(job_id: str) -> JobAnswer:
        return service.run(service.get(job_id, "run"))

    @app.delete("/v1/runs/{job_id}", response_model=JobAnswer, responses=_ERRORS,
                summary="Cancel a run")
    def cancel_run(job_id: str) -> JobAnswer:
        service.get(job_id, "run")
        job = service.jobs.cancel(job_id)
        if job is None:  # pruned meanwhile
            raise Refused(404, f"no run job {job_id!r} on this server")
        return service.run(job)

    @app.get("/v1/runs/{job_id}/events", summary="A run's progress as server-sent events",
             response_class=StreamingResponse,
             responses={200: {"content": {"text/event-stream": {}}}})
    def run_events(job_id: str, request: Request) -> StreamingResponse:
        service.get(job_id, "run")
        start = request.headers.get("last-event-id", "0")
        after = int(start) if start.isascii() and start.isdigit() and len(start) < 12 else 0
        return StreamingResponse(_events(service.jobs, job_id, after),
                                 media_type="text/event-stream",
                                 headers={"Cache-Control": "no-store"})

    @app.get("/v1/files/{job_id}/{name}", summary="A job's picture, render or video",
             responses={200: {"content": {"image/png": {}, "video/mp4": {}}}})
    def file(job_id: str, name: str, request: Request) -> Response:
        found = service.jobs.file(job_id, name)
        if found is None:
            raise Refused(404, f"no file {name!r} for job {job_id!r}")
        media, data = found
        # Behind a token the answer is the client's own; a shared cache must not keep it.
        cache = "private" if config.token else "public"
        headers = {"Cache-Control": f"{cache}, max-age=86400, immutable",
                   "Accept-Ranges": "bytes"}
        wanted = request.headers.get("range")
        if wanted is None:
            return Response(data, media_type=media, headers=headers)
        # A phone's video player asks for byte ranges, and plays nothing without them.
        first, last = _byte_range(wanted, len(data))
        headers["Content-Range"] = f"bytes {first}-{last}/{len(data)}"
        return Response(data[first:last + 1], status_code=206, media_type=media,
                        headers=headers)

    @app.post("/v1/preferences", response_model=PreferencesAnswer, responses=_ERRORS,
              summary="Learn preferences from example table settings")
    async def post_preferences(body: PreferencesBody, request: Request) -> PreferencesAnswer:
        from llm_grop.arrangement.learning import learn
        from llm_grop.world.catalog import Catalog

        if body.generalise:  # an LLM call: queued as a job, as an arrangement is
            job_id = await run_in_threadpool(service.submit, "learn", body, client(request))
            return service.preferences(await service.finished(job_id))
        return preferences_answer(await run_in_threadpool(learn, body.examples,
                                                          Catalog.load()))

    @app.get("/v1/preferences/{job_id}", response_model=PreferencesAnswer,
             responses=_ERRORS, summary="Preferences learned with the LLM's step, at their "
                                        "permalink")
    async def get_preferences(job_id: str) -> PreferencesAnswer:
        job = await run_in_threadpool(service.get, job_id, "learn")
        return service.preferences(await service.finished(job.id))

    add_playground(app, service)
    return app


#: The body each endpoint takes, whose keys an unknown one is matched against.
_BODIES: dict[str, type[BaseModel]] = {"/v1/arrangements": ArrangeBody, "/v1/plans": PlanBody,
                                       "/v1/runs": RunBody, "/v1/preferences": PreferencesBody}


async def _events(jobs: JobStore, job_id: str, after: int) -> AsyncIterator[str]:
    while True:
        for seq, at, message in await run_in_threadpool(jobs.events, job_id, after):
            after = seq
            data = json.dumps({"at": at, "message": message})
            yield f"id: {seq}\nevent: progress\ndata: {data}\n\n"
        job = await run_in_threadpool(jobs.get, job_id)
        if job is None or job.terminal:
            state = job.state if job is not None else "gone"
            data = {"state": state, "error": job.error if job is not None else None}
            yield f"event: end\ndata: {json.dumps(data)}\n\n"
            return
        await asyncio.sleep(EVENTS_POLL_S)


def _byte_range(header: str, size: int) -> tuple[int, int]:
    """The first and last byte of a ``Range: bytes=a-b`` header (one range); 416 when it
    does not fit a body of ``size`` bytes."""
    unit, _, spec = header.partition("=")
    first_text, dash, last_text = spec.strip().partition("-")
    try:
        if unit.strip() != "bytes" or not dash or "," in spec:
            raise ValueError
        if first_text:
            first = int(first_text)
            last = min(int(last_text), size - 1) if last_text else size - 1
        else:
            first, last = max(size - int(last_text), 0), size - 1
    except ValueError:
        raise Refused(416, f"range: expected bytes=FIRST-LAST, got {header[:40]!r}") from None
    if first > last or first >= size:
        raise Refused(416, f"range: {header[:40]!r} is outside the file's {size} bytes")
    return first, last


def _version() -> str:
    try:
        return metadata.version("llm-grop")
    except metadata.PackageNotFoundError:
        return "0"
