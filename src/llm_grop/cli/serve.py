"""``llm-grop serve``: the planning service for robot stacks, and its playground page."""

from __future__ import annotations

import json
import os
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import click

from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG, check_out_dir
from llm_grop.cli.settings import LLM_FIELDS, flags, from_flags
from llm_grop.errors import INTERNAL_ERROR_EXIT, BadInput


def read_timeouts(command: Any) -> Any:
    """``--header-timeout`` and ``--body-timeout`` on ``command``: both web servers'
    (``serve``, ``ratings serve``) seconds a client has to send a request."""
    command = click.option(
        "--body-timeout", "body_timeout_s", default=30.0, show_default=True,
        type=click.FloatRange(0.1, 3600),
        help="Seconds a client has to send a request's body once its headers are in; then "
             "408 and the connection is closed.")(command)
    return click.option(
        "--header-timeout", "header_timeout_s", default=10.0, show_default=True,
        type=click.FloatRange(0.1, 3600),
        help="Seconds a client has to send a request's line and headers (from connecting, "
             "or from the request's first byte); then 408 and the connection is "
             "closed.")(command)


def _default_db() -> Path:
    base = os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share"
    return Path(base) / "llm-grop" / "serve.sqlite"


@click.command(epilog=EPILOG)
@VERBOSE
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Address to bind; any but loopback needs --token.")
@click.option("--port", default=8000, show_default=True, type=click.IntRange(0, 65535),
              help="Port to bind (0: any free one).")
@click.option("--llm", "backends", multiple=True, default=("embedded",), show_default=True,
              help="An LLM backend clients may choose by name (repeatable; the first is the "
                   "default): embedded, openai, replay, auto (what `--llm auto` finds when "
                   "the server starts), or a plugin's.")
@flags(*(f for f in LLM_FIELDS if f != "llm"))
@click.option("--workers", default=2, show_default=True, type=click.IntRange(1, 64),
              help="Worker processes that run jobs.")
@click.option("--llm-threads", type=click.IntRange(1),
              help="The embedded model's CPU threads per worker [default: cores over "
                   "--workers].")
@click.option("--db", "db", type=click.Path(dir_okay=False, path_type=Path),
              help="SQLite file of jobs and results [default: "
                   "$XDG_DATA_HOME/llm-grop/serve.sqlite].")
@click.option("--token", envvar="LLM_GROP_TOKEN",
              help="Bearer token every request must carry (at least 16 characters; "
                   "default $LLM_GROP_TOKEN); needed to bind other than loopback.")
@click.option("--max-run-time", "run_time_s", default=600.0, show_default=True,
              type=click.FloatRange(1), help="Seconds a job may run before it is failed.")
@click.option("--queue", default=64, show_default=True, type=click.IntRange(1),
              help="Jobs that may wait at once; more are answered 429.")
@click.option("--runs-per-client", default=4, show_default=True, type=click.IntRange(1),
              help="Runs one client address may have waiting or running; more get 429.")
@click.option("--keep-days", default=30.0, show_default=True,
              type=click.FloatRange(0, min_open=True),
              help="Days an ended job's result, pictures and video are kept for its "
                   "permalink; older ones are deleted hourly.")
@read_timeouts
@click.option("--openapi", is_flag=True,
              help="Print the OpenAPI document (docs/schema/openapi.json) and exit.")
def serve(host: str, port: int, backends: tuple[str, ...], replay: Path | None,
          workers: int, llm_threads: int | None, db: Path | None, token: str | None,
          run_time_s: float, queue: int, runs_per_client: int, keep_days: float,
          header_timeout_s: float, body_timeout_s: float, openapi: bool,
          **flags: Any) -> None:
    """Serve the JSON API (/v1/) and the playground page (/) over HTTP.

    Needs `pip install 'llm-grop[serve]'`. The LLM backends and their keys stay on the
    server; clients choose among --llm by name (GET /v1/info lists them).
    """
    try:
        import httptools  # noqa: F401 - the HTTP parser the server's deadlines sit on
        import uvicorn  # noqa: F401

        from llm_grop.service.app import create_app
    except ImportError as exc:
        raise BadInput(f"serve: needs the serve extra (pip install 'llm-grop[serve]'): "
                       f"{exc.name} is missing") from None
    from llm_grop.llm.registry import BACKENDS
    from llm_grop.service.config import Backend, Limits, ServiceConfig, check_bind

    check_bind(host, token)
    from llm_grop.assembly import AUTO, backend_options, resolve_llm

    settings = from_flags(flags, replay=replay.absolute() if replay else None)
    # ``auto`` is resolved once, at start: the server offers what it found, by name.
    built = {}
    for given in dict.fromkeys(backends):
        made = settings
        if given == AUTO:
            made, choice = resolve_llm(settings.with_values(llm=AUTO))
            click.echo(f"llm-grop serve: --llm auto: {choice.note if choice else ''}")
        built.setdefault(BACKENDS.key(made.llm if given == AUTO else given), made)
    names = list(built)
    if "replay" in names and replay is None:
        raise BadInput("needs --replay FILE, a JSONL file of recorded calls", param="llm",
                       value="replay")
    if replay is not None and not replay.is_file():
        raise BadInput("no such file", param="replay", value=replay)
    from llm_grop.llm.registry import backend_options_class
    from llm_grop.settings.declared import declared_options

    # Each backend offered takes --llm-option, checked against what it declares.
    offered = tuple(Backend(n, replace(backend_options(made), own=declared_options(
        backend_options_class(n), dict(made.backend_options),
        owner=f"LLM backend {n!r}", param="backend_options"))) for n, made in built.items())
    db = (db or _default_db()).expanduser().absolute()
    check_out_dir("db", db.parent)
    db.parent.mkdir(parents=True, exist_ok=True)  # checked above: it can be made
    config = ServiceConfig(db=db, backends=offered,
                           workers=workers, token=token,
                           limits=Limits(run_time_s=run_time_s, queue=queue,
                                         jobs_per_client=runs_per_client),
                           llm_threads=llm_threads or max(1, (os.cpu_count() or 1) // workers),
                           keep_s=keep_days * 86400)
    if openapi:
        click.echo(json.dumps(create_app(config, workers=False).openapi(), indent=2))
        return
    from llm_grop.web import listen, run, url_of

    sock = listen(host, port)
    app = create_app(config)
    click.echo(f"llm-grop serve: {url_of(sock)} (jobs in {db}; backends "
               f"{', '.join(names)}; {workers} workers)", err=True)
    # No proxy headers: a client on this machine could otherwise claim any address and
    # escape its per-client limits.
    try:
        started = run(app, sock, header_timeout_s=header_timeout_s,
                      body_timeout_s=body_timeout_s, graceful_s=5)
    except KeyboardInterrupt:
        return  # SIGINT or SIGTERM: shut down gracefully, which is no error for a server
    if not started:
        click.echo("llm-grop serve: the server did not start; the log above says why",
                   err=True)
        sys.exit(INTERNAL_ERROR_EXIT)
