"""The playground at ``/``: a page rendered on the server, over the same jobs as the JSON
API, that works without JavaScript (``static/play.js`` only fills in examples, shows that
work is under way and follows a run's events instead of reloading).

Each result has a permalink (``/a/ID``, ``/p/ID``, ``/r/ID``); the browser's short history
of them is a cookie, so no list of other people's requests is ever shown. Forms are
refused when posted from another site (their Origin must be this server's).
"""

from __future__ import annotations

import math
import re
from functools import cache
from typing import Annotated, Any

import jinja2
from fastapi import FastAPI, Form, Request
from fastapi.responses import HTMLResponse, RedirectResponse, Response
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, ConfigDict, Field, ValidationError
from starlette.concurrency import run_in_threadpool

from llm_grop.contract.models import ArrangementDoc
from llm_grop.service.http import Refused
from llm_grop.service.jobs import Job
from llm_grop.service.models import (
    ArrangeBody,
    PlanBody,
    RunBody,
    TableBody,
    one_line,
)
from llm_grop.service.service import Service, StillRunning
from llm_grop.settings import DEFAULTS, words
from llm_grop.web import same_origin

HISTORY_COOKIE = "llm_grop_history"
#: Results the history cookie keeps.
HISTORY = 8
EXAMPLES = (
    "set the table with a dinner plate, a dinner fork and a dinner knife",
    "a dinner plate, a dinner fork, a dinner knife, a mug and a mug lid",
    "a bread plate, a dinner plate and a water cup",
)
_PREFIX = {"arrange": "a", "plan": "p", "run": "r"}
_KIND = {v: k for k, v in _PREFIX.items()}
_ID = re.compile(r"^[A-Za-z0-9_-]{1,32}$")


def kind_class(kind: str) -> str:
    """The CSS class of an object kind's colour swatch."""
    return "k-" + re.sub(r"[^a-z0-9]+", "-", kind.lower()).strip("-")


@cache
def environment() -> jinja2.Environment:
    """The page templates beside this module, HTML-escaped."""
    env = jinja2.Environment(loader=jinja2.PackageLoader("llm_grop.service", "templates"),
                             autoescape=True, undefined=jinja2.StrictUndefined)
    env.filters["kind_class"] = kind_class
    return env


def add_playground(app: FastAPI, service: Service) -> None:
    """Add the playground's pages to ``app``."""
    from importlib import resources

    static = resources.files("llm_grop.service").joinpath("static")
    app.mount("/static", StaticFiles(directory=str(static)), name="static")
    config = service.config

    def page(request: Request, status: int = 200, **context: Any) -> HTMLResponse:
        from llm_grop.api import available_simulators

        base = {"error": None, "job": None, "form": _form(request.query_params),
                "examples": EXAMPLES, "backends": [b.name for b in config.backends],
                "simulators": available_simulators(), "limits": config.limits,
                "history": _history(request, service)}
        html = environment().get_template("play.html").render(**(base | context))
        return HTMLResponse(html, status_code=status, headers={"Cache-Control": "no-store"})

    app.state.page_error = lambda request, status, message: page(request, status,
                                                                 error=message)

    @app.get("/", response_class=HTMLResponse, include_in_schema=False)
    def index(request: Request) -> HTMLResponse:
        return page(request)

    @app.get("/favicon.ico", include_in_schema=False)
    def favicon() -> Response:
        # Browsers ask for /favicon.ico whatever the page links; the icon is an SVG.
        return RedirectResponse("/static/favicon.svg", status_code=301)

    @app.get("/kinds.css", include_in_schema=False)
    async def kinds_css() -> Response:
        from llm_grop.render.table import kind_color
        from llm_grop.world.catalog import Catalog

        rules = [f".{kind_class(name)} {{ background: {kind_color(name)}; }}"
                 for name in Catalog.load().names()]
        return Response("\n".join(rules) + "\n", media_type="text/css",
                        headers={"Cache-Control": "public, max-age=3600"})

    @app.post("/play", include_in_schema=False)
    async def play(request: Request, posted: Annotated[PlayForm, Form()]) -> Response:
        _check_origin(request)
        fields = posted.model_dump(exclude={"action"})
        try:
            kind, body = _body(posted.action, fields)
        except ValidationError as exc:
            return await run_in_threadpool(page, request, 422, form=_form(fields),
                                           error=one_line(exc.errors(), where=None))
        except ValueError as exc:
            return await run_in_threadpool(page, request, 422, form=_form(fields),
                                           error=str(exc))
        client = request.client.host if request.client is not None else "?"
        try:
            job_id = await run_in_threadpool(service.submit, kind, body,  # type: ignore[arg-type]
                                             client)
            if kind != "run":
                await service.finished(job_id)
        except Refused as exc:
            return await run_in_threadpool(page, request, exc.status, form=_form(fields),
                                           error=exc.message)
        except StillRunning:
            pass  # its page says so, and follows it
        answer = RedirectResponse(f"/{_PREFIX[kind]}/{job_id}", status_code=303)
        _remember(answer, request, f"{_PREFIX[kind]}:{job_id}")
        return answer

    @app.get("/{prefix}/{job_id}", response_class=HTMLResponse, include_in_schema=False)
    def result(request: Request, prefix: str, job_id: str) -> HTMLResponse:
        if prefix not in _KIND or not _ID.match(job_id):
            raise Refused(404, f"no page {request.url.path!r}")
        job = service.get(job_id, _KIND[prefix])  # type: ignore[arg-type]
        status = job.status or 500 if job.state == "failed" else 200
        return page(request, status, form=_form(_fields(job)), **_result(service, job))


class PlayForm(BaseModel):
    """The playground's form as posted: every field text, as a browser sends it, read into
    an API body by :func:`_body`."""

    model_config = ConfigDict(extra="ignore")

    action: str = Field(max_length=10)
    request: str = Field(max_length=2000)
    llm: str = Field("", max_length=64)
    shape: str = Field("rectangle", max_length=16)
    width_cm: str = Field("90", max_length=16)
    depth_cm: str = Field("60", max_length=16)
    diners: str = Field("1", max_length=4)
    seed: str = Field(str(DEFAULTS.seed), max_length=12)
    simulator: str = Field(DEFAULTS.simulator, max_length=32)
    preferences: str = Field("", max_length=4000)
    #: ``on``: the LLM may add what the request leaves out (the API's ``guess``).
    guess: str = Field("on" if DEFAULTS.guess else "off", max_length=3)


def _check_origin(request: Request) -> None:
    """Refuse a form posted from another site, or with no Origin to tell."""
    if not same_origin(request.headers.get("origin"), request.headers.get("host")):
        raise Refused(403, "form posted from another site (or without an Origin header)")


def _body(action: str, fields: dict[str, str]) -> tuple[str, ArrangeBody | PlanBody]:
    """The API body a form asks for."""
    def number(name: str, text: str) -> float:
        try:
            value = float(text)
            if not math.isfinite(value) or abs(value) >= 2**31:
                raise ValueError
        except ValueError:
            raise ValueError(f"{name}: expected a number, got {text[:20]!r}") from None
        return value

    width, depth = number("width_cm", fields["width_cm"]), number("depth_cm", fields["depth_cm"])
    table = TableBody(shape=fields["shape"], size=(width / 100, width / 100)  # type: ignore[arg-type]
                      if fields["shape"] == "circle" else (width / 100, depth / 100))
    prefs = [line.strip() for line in fields["preferences"].splitlines() if line.strip()]
    common: dict[str, Any] = {"request": fields["request"].strip(), "table": table,
                              "preferences": prefs, "seed": int(number("seed", fields["seed"])),
                              "llm": fields["llm"] or None, "guess": fields["guess"] != "off"}
    if action == "arrange":
        # One diner is the form's default, "as the request says"; any other count goes to
        # the API's body, which refuses 0, -1 or 2.5 in its own words.
        diners = number("diners", fields["diners"])
        count = int(diners) if diners.is_integer() else diners
        return "arrange", ArrangeBody(**common, diners=None if count == 1 else count)
    if action == "plan":
        return "plan", PlanBody(**common)
    if action == "run":
        return "run", RunBody(**common, simulator=fields["simulator"])
    raise ValueError(f"action: expected arrange, plan or run, got {action!r}")


def _form(values: Any) -> dict[str, str]:
    """The form's fields, as given or by default."""
    defaults = {"request": "", "llm": "", "shape": "rectangle", "width_cm": "90",
                "depth_cm": "60", "diners": "1", "seed": str(DEFAULTS.seed),
                "simulator": DEFAULTS.simulator, "preferences": "",
                "guess": "on" if DEFAULTS.guess else "off"}
    return {k: str(values.get(k, v) or v) if k != "request" else str(values.get(k, v))
            for k, v in defaults.items()}


def _fields(job: Job) -> dict[str, str]:
    """A job's request as the form's fields, to edit and resubmit."""
    b = job.body
    table = b.get("table") or {}
    size = table.get("size") or [0.9, 0.6]
    return {"request": b.get("request") or "", "llm": b.get("llm") or "",
            "shape": table.get("shape", "rectangle"), "width_cm": f"{size[0] * 100:g}",
            "depth_cm": f"{size[1] * 100:g}", "diners": str(b.get("diners") or 1),
            "seed": str(b.get("seed", 0)), "simulator": b.get("simulator", DEFAULTS.simulator),
            "preferences": "\n".join(b.get("preferences") or []),
            "guess": "off" if b.get("guess") is False else "on"}


def _result(service: Service, job: Job) -> dict[str, Any]:
    """What the result page shows for ``job``."""
    files = set(service.jobs.files(job.id))
    url = f"/v1/files/{job.id}/"
    out: dict[str, Any] = {"job": job, "permalink": f"/{_PREFIX[job.kind]}/{job.id}",
                           "events": [m for _, _, m in service.jobs.events(job.id)],
                           "arrangement": None, "pictures": [], "video": None,
                           "recording": None, "summary": None}
    result = job.result or {}

    def web(doc: ArrangementDoc) -> ArrangementDoc:
        # Its warnings name the playground's own controls, not the API's parameters.
        return doc.model_copy(update={"warnings": [words(w, "web") for w in doc.warnings]})

    def picture(name: str, alt: str, caption: str, phone: str | None = None) -> None:
        if name in files:
            out["pictures"].append({"url": url + name, "alt": alt, "caption": caption,
                                    "id": name.removesuffix(".png").replace("_", "-"),
                                    "phone": url + phone if phone in files else None})

    if job.kind == "arrange" and "arrangement" in result:
        out["arrangement"] = doc = web(ArrangementDoc.model_validate(result["arrangement"]))
        diners = len(doc.table.diners or ()) or 1
        where = "the diner sits at the bottom" if diners == 1 else \
            f"{diners} diners, each drawn at their seat and labelled"
        picture("table.png", "The arrangement from above",
                f"The arrangement, from above ({where})", "table_phone.png")
    elif job.kind == "plan" and "plan" in result:
        plan = result["plan"]
        out["arrangement"] = web(ArrangementDoc.model_validate(plan["arrangement"]))
        s = plan["plan"]
        out["summary"] = (f"{len(plan['steps'])} steps; expected utility "
                          f"{s['expected_utility']:.1f} s, expected duration "
                          f"{s['expected_duration_s']:.1f} s")
        picture("room.png", "The plan in the room", "The plan: paths and standing positions")
        picture("table.png", "The planned arrangement", "The planned arrangement",
                "table_phone.png")
    elif job.kind == "run" and "run" in result:
        run = result["run"]
        out["arrangement"] = web(ArrangementDoc.model_validate(run["planned"]))
        out["summary"] = (f"{'success' if run['success'] else 'failed'}: execution "
                          f"{run['execution_time_s']:.1f} s, {run['failures']} failed "
                          f"attempt{'s' * (run['failures'] != 1)}, in {run['simulator']}")
        picture("room.png", "The run in the room", "The run: the robot's paths")
        picture("table.png", "The table as executed", "The table as executed",
                "table_phone.png")
        picture("render_table.png", "The table rendered in 3D", "MuJoCo: the table")
        picture("render_room.png", "The room rendered in 3D", "MuJoCo: the room")
        if "episode.mp4" in files:
            out["video"] = url + "episode.mp4"
        if "episode.rrd" in files:
            out["recording"] = url + "episode.rrd"
    return out


def _history(request: Request, service: Service) -> list[dict[str, str]]:
    """The browser's recent results, newest first, that still exist."""
    out = []
    for entry in request.cookies.get(HISTORY_COOKIE, "").split("."):
        prefix, _, job_id = entry.partition(":")
        if prefix not in _KIND or not _ID.match(job_id) or service.store is None:
            continue
        job = service.jobs.get(job_id)
        if job is not None:
            text = job.body.get("request") or f"task {job.body.get('task')}"
            out.append({"url": f"/{prefix}/{job_id}", "label": text[:80],
                        "kind": job.kind, "state": job.state})
    return out


def _remember(response: Response, request: Request, entry: str) -> None:
    kept = [e for e in request.cookies.get(HISTORY_COOKIE, "").split(".") if e and e != entry]
    response.set_cookie(HISTORY_COOKIE, ".".join([entry, *kept][:HISTORY]),
                        max_age=30 * 86400, httponly=True, samesite="strict", path="/")
