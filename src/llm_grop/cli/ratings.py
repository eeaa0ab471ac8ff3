"""``llm-grop ratings``: a human rating study of a bench's pictures (paper §IV).

``create`` makes a study database from a bench directory, ``invite`` prints invite codes,
``serve`` runs the rating website, ``export`` writes every rating as CSV and ``report``
writes the figures of merit from the human ratings.
"""

from __future__ import annotations

import secrets
from pathlib import Path

import click

from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG, check_out_dir, check_outputs
from llm_grop.cli.serve import read_timeouts
from llm_grop.errors import BadInput

DB = click.option("--db", "db", required=True, type=click.Path(dir_okay=False, path_type=Path),
                  help="The study's SQLite database file.")
#: Shortest admin token accepted, characters.
MIN_TOKEN_CHARS = 16


def _extra(module: str) -> None:
    """A one-line error when the ``ratings`` extra is not installed."""
    try:
        __import__(module)
    except ImportError:
        raise BadInput(f"ratings: needs {module}, from the 'ratings' extra: pip install "
                       "'llm-grop[ratings]'") from None


@click.group(epilog=EPILOG)
@VERBOSE
def ratings() -> None:
    """A human rating study of a bench's pictures: create, invite, serve, export, report."""


@ratings.command(epilog=EPILOG)
@VERBOSE
@click.option("--bench", "bench_dir", required=True,
              type=click.Path(file_okay=False, path_type=Path),
              help="A directory 'llm-grop bench --out' wrote (with its pictures).")
@DB
@click.option("--name", help="The study's name (default: the bench directory's name).")
@click.option("--seed", default=0, show_default=True, type=click.IntRange(min=0),
              help="Seeds each rater's order of the pictures.")
def create(bench_dir: Path, db: Path, name: str | None, seed: int) -> None:
    """Make a study of the bench's trial pictures in a new database."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

    from llm_grop.ratings.study import create_study, items_from_bench

    check_outputs(db=db)
    if db.exists():
        raise BadInput(f"--db {db}: already exists; a study is made once, in a new file")
    console = Console(stderr=True)
    with Progress(TextColumn("pictures"), BarColumn(), MofNCompleteColumn(),
                  console=console, transient=True) as progress:
        bar = progress.add_task("pictures", total=None)
        items = items_from_bench(bench_dir, on_picture=lambda k, n: progress.update(
            bar, completed=k, total=n))
    info = create_study(db, items, name=name or bench_dir.resolve().name,
                        source=str(bench_dir), seed=seed)
    from llm_grop.ratings.report import counted

    click.echo(f"Study '{info.name}': {counted(info.items, 'picture')} of "
               f"{'task' if len(info.tasks) == 1 else 'tasks'} "
               f"{', '.join(map(str, info.tasks))} by {counted(len(info.methods), 'method')}, "
               f"in {db}")
    click.echo(f"Next: llm-grop ratings invite --db {db} --count 5")


@ratings.command(epilog=EPILOG)
@VERBOSE
@DB
@click.option("--count", required=True, type=int, help="How many raters to invite.")
def invite(db: Path, count: int) -> None:
    """Invite COUNT raters: prints one invite code per line."""
    from llm_grop.ratings.study import invite as invite_raters

    for code in invite_raters(db, count):
        click.echo(code)


@ratings.command(epilog=EPILOG)
@VERBOSE
@DB
@click.option("--host", default="127.0.0.1", show_default=True, help="Address to listen on.")
@click.option("--port", default=8000, show_default=True, type=click.IntRange(0, 65535),
              help="Port to listen on (0: any free port).")
@click.option("--admin-token", envvar="LLM_GROP_ADMIN_TOKEN", show_envvar=True,
              help="Bearer token of the admin endpoints (default: a new one, printed).")
@click.option("--session-hours", default=8.0, show_default=True,
              type=click.FloatRange(min=0.01, max=24 * 30),
              help="How long a rater's session lasts.")
@click.option("--forwarded-allow-ips", "proxy_ips", envvar="FORWARDED_ALLOW_IPS",
              show_envvar=True, default="",
              help="Addresses of the HTTPS proxies whose X-Forwarded-For and "
                   "X-Forwarded-Proto are trusted (comma-separated, or *) [default: none, "
                   "so no client can claim another address]. Behind a proxy, list it (also "
                   "127.0.0.1 for one on this machine): else cookies lack the Secure flag "
                   "and every rater shares the proxy's address for the join limit.")
@read_timeouts
def serve(db: Path, host: str, port: int, admin_token: str | None,
          session_hours: float, proxy_ips: str, header_timeout_s: float,
          body_timeout_s: float) -> None:
    """Serve the rating website for the study in the database."""
    _extra("fastapi")
    _extra("uvicorn")
    _extra("httptools")
    from llm_grop.ratings.app import create_app
    from llm_grop.ratings.study import study_info
    from llm_grop.web import listen, run, url_of

    if admin_token is not None and len(admin_token.strip()) < MIN_TOKEN_CHARS:
        raise BadInput(f"--admin-token: use at least {MIN_TOKEN_CHARS} characters")
    generated = admin_token is None
    token = secrets.token_urlsafe(24) if admin_token is None else admin_token.strip()
    info = study_info(db)
    app = create_app(db, admin_token=token, ttl_s=session_hours * 3600)
    sock = listen(host, port)
    click.echo(f"Serving study '{info.name}' ({info.items} pictures, {info.raters} raters) at "
               f"{url_of(sock)}  (Ctrl-C stops)", err=True)
    if generated:
        click.echo(f"Admin token: {token} (give --admin-token or set LLM_GROP_ADMIN_TOKEN "
                   "to choose one)", err=True)
    run(app, sock, header_timeout_s=header_timeout_s, body_timeout_s=body_timeout_s,
        forwarded_allow_ips=proxy_ips.strip() or None)


@ratings.command(epilog=EPILOG)
@VERBOSE
@DB
@click.option("--csv", "csv_path", required=True,
              type=click.Path(dir_okay=False, allow_dash=True, path_type=Path),
              help="Where to write the ratings as CSV ('-': standard output).")
def export(db: Path, csv_path: Path) -> None:
    """Write every rating, with its trial and method, as CSV."""
    from llm_grop.files.jsonio import write_text
    from llm_grop.ratings.db import connect
    from llm_grop.ratings.store import RatingStore, export_csv

    to_stdout = str(csv_path) == "-"
    if not to_stdout:
        check_outputs(csv=csv_path)
    conn = connect(db)
    try:
        rows = RatingStore(conn).export_rows()
    finally:
        conn.close()
    if to_stdout:
        click.echo(export_csv(rows), nl=False)
        return
    write_text(csv_path, export_csv(rows))
    click.echo(f"Wrote {len(rows)} ratings: {csv_path}", err=True)


@ratings.command(epilog=EPILOG)
@VERBOSE
@DB
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False,
                                                                 path_type=Path),
              help="Directory for report.md, report.json, report.html and the figures.")
def report(db: Path, out_dir: Path) -> None:
    """Write the human ratings' report: means, agreement, paired tests, Fig. 3 and 5."""
    _extra("krippendorff")
    _extra("jinja2")
    from rich.console import Console

    from llm_grop.experiment.summary import rich_table
    from llm_grop.ratings.db import connect
    from llm_grop.ratings.report import human_report, sections, write_report

    check_out_dir("out", out_dir)
    conn = connect(db)
    try:
        result = human_report(conn)
    finally:
        conn.close()
    if result.ratings == 0:
        raise BadInput(f"--db {db}: no rating yet; nothing to report")
    written = write_report(result, out_dir)
    out = Console()
    s = sections(result)
    out.print(s["headline"])
    out.print(rich_table("Results per method (mean ± standard error)", *s["per_method"]))
    out.print(rich_table("Mean rating (1-5) per task, ± SE", *s["per_task"], left=0))
    for k, v in s["agreement"]:
        out.print(f"{k}: {v}")
    out.print(f"Wrote {len(written)} files to {out_dir}")
