"""What the JSON API and the playground share: checking a request before it is queued,
queueing it, waiting for its job, and its answer as the API's models."""

from __future__ import annotations

import asyncio
import logging
from dataclasses import dataclass, field

from starlette.concurrency import run_in_threadpool

from llm_grop.contract.models import ArrangementDoc
from llm_grop.service.config import ServiceConfig
from llm_grop.service.http import Refused
from llm_grop.service.jobs import Job, JobStore, Kind, Overloaded
from llm_grop.service.models import (
    ArrangeBody,
    ArrangementAnswer,
    JobAnswer,
    PlanAnswer,
    PlanBody,
    PreferencesAnswer,
    PreferencesBody,
    RunBody,
    reading,
)
from llm_grop.service.storage import Episode, Unwritable, state

log = logging.getLogger(__name__)

#: Seconds between looks at a job a request waits for.
WAIT_POLL_S = 0.02


class StillRunning(Exception):
    """A job that has not ended within the server's wait: answered 202 with where its
    answer will be."""

    def __init__(self, job: Job) -> None:
        super().__init__(f"{job.kind} {job.id} still {job.state}")
        self.job = job


@dataclass
class Service:
    """A server's configuration and its job store (``None`` in an app made only to
    publish its OpenAPI document); ``storage``, when its disk last refused new work."""

    config: ServiceConfig
    store: JobStore | None
    storage: Episode = field(default_factory=lambda: Episode(
        "llm-grop serve", log, "new work is refused with 503 until it takes writes again"))

    @property
    def jobs(self) -> JobStore:
        """The job store."""
        assert self.store is not None, "the app was made without its workers"
        return self.store

    def check(self, body: ArrangeBody | PlanBody | PreferencesBody) -> None:
        """Refuse what is plainly wrong before a job is queued: a request over the
        server's length, a backend, method or simulator it does not offer."""
        from llm_grop.api import available_methods, available_simulators
        from llm_grop.service.tasks import check_plugin_options

        if isinstance(body, PreferencesBody):
            self.config.backend(body.llm)
            return
        text = body.request or ""
        limit = self.config.limits.request_chars
        if len(text) > limit:
            raise Refused(422, f"request: {len(text)} characters; this server reads at most "
                               f"{limit}")
        self.config.backend(body.llm)
        if isinstance(body, PlanBody) and body.method not in available_methods():
            raise Refused(422, f"method: unknown method {body.method!r}; choose from "
                               f"{', '.join(available_methods())}")
        if isinstance(body, RunBody) and body.simulator not in available_simulators():
            raise Refused(422, f"simulator: unknown simulator {body.simulator!r}; choose "
                               f"from {', '.join(available_simulators())}")
        check_plugin_options(body)

    def submit(self, kind: Kind, body: ArrangeBody | PlanBody | PreferencesBody,
               client: str) -> str:
        """Queue a checked job for ``client`` (its address); its id. 429 when the queue is
        full; :class:`Unwritable` (503) while the disk is full or read-only."""
        self.check(body)
        refused = state(self.config.db.parent)
        if refused is not None:
            raise Unwritable(refused)
        limits = self.config.limits
        try:
            job_id = self.jobs.submit(kind, body.model_dump(mode="json", exclude_unset=True),
                                      client, queue=limits.queue,
                                      per_client=limits.jobs_per_client if kind == "run"
                                      else limits.requests_per_client)
        except Overloaded as exc:
            raise Refused(429, str(exc), {"Retry-After": str(exc.retry_after_s)}) from None
        self.storage.cleared()
        return job_id

    async def finished(self, job_id: str) -> Job:
        """The job once it has ended; 504 after the server's wait."""
        loop = asyncio.get_running_loop()
        wait = self.config.limits.wait_s
        deadline = loop.time() + wait
        while True:
            job = await run_in_threadpool(self.jobs.get, job_id)
            if job is None:  # pruned while it was waited for
                raise Refused(404, f"no job {job_id!r} on this server")
            if job.terminal:
                return job
            if loop.time() > deadline:
                raise StillRunning(job)
            await asyncio.sleep(WAIT_POLL_S)

    def get(self, job_id: str, kind: Kind) -> Job:
        """The job ``job_id`` of ``kind``; 404 otherwise."""
        job = self.jobs.get(job_id)
        if job is None or job.kind != kind:
            raise Refused(404, f"no {kind} job {job_id!r} on this server")
        return job

    def arrangement(self, job: Job) -> ArrangementAnswer:
        """An ended arrangement job's answer (its failure as a refusal)."""
        result = _result(job)
        doc = ArrangementDoc.model_validate(result["arrangement"])
        return ArrangementAnswer(id=job.id, arrangement=doc, reading=reading(doc),
                                 warnings=list(doc.warnings),
                                 picture=f"/v1/files/{job.id}/table.png",
                                 permalink=f"/v1/arrangements/{job.id}")

    def plan(self, job: Job) -> PlanAnswer:
        """An ended plan job's answer (its failure as a refusal)."""
        plan = _result(job)["plan"]
        doc = ArrangementDoc.model_validate(plan["arrangement"])
        return PlanAnswer(id=job.id, plan=plan, reading=reading(doc),
                          warnings=list(doc.warnings), picture=f"/v1/files/{job.id}/table.png",
                          room_picture=f"/v1/files/{job.id}/room.png",
                          permalink=f"/v1/plans/{job.id}")

    def preferences(self, job: Job) -> PreferencesAnswer:
        """An ended learning job's answer (its failure as a refusal)."""
        answer = PreferencesAnswer.model_validate(_result(job)["preferences"])
        return answer.model_copy(update={"id": job.id,
                                         "permalink": f"/v1/preferences/{job.id}"})

    def run(self, job: Job) -> JobAnswer:
        """A run job as it stands."""
        result = job.result.get("run") if job.result is not None else None
        return JobAnswer(id=job.id, kind=job.kind, state=job.state, created=job.created,
                         started=job.started, finished=job.finished, attempts=job.attempts,
                         error=job.error, status=job.status, result=result,
                         files={n: f"/v1/files/{job.id}/{n}" for n in self.jobs.files(job.id)},
                         events=f"/v1/runs/{job.id}/events", permalink=f"/v1/runs/{job.id}")


def _result(job: Job) -> dict:
    if job.state != "done" or job.result is None:
        raise Refused(job.status or 500, job.error or job.state)
    return job.result
