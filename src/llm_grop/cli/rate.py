"""``llm-grop rate``: the automatic 1-5 rating of an arrangement JSON (paper Table III)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import click

from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG
from llm_grop.errors import BadInput


def read_rating_input(path: Path) -> tuple[dict[str, Any], str | None, str]:
    """``(arrangement, run request, where)`` from an arrangement or run JSON file.

    A run JSON (one with a ``final`` key) gives its ``final`` arrangement, with the
    run's ``request`` as the request when it has one.
    """
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise BadInput(f"{path}: cannot read ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise BadInput(f"{path}: not UTF-8 text") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise BadInput(f"{path}: not valid JSON (line {exc.lineno}: {exc.msg})") from None
    if not isinstance(data, dict):
        raise BadInput(f"{path}: expected a JSON object (an arrangement or a run JSON)")
    if "final" not in data:
        return data, None, str(path)
    # Only `final` and `request` of a run JSON are read (and `final` is validated by the
    # rater as an arrangement): a run written by another system may lack the rest.
    final = data["final"]
    if not isinstance(final, dict):
        raise BadInput(f"{path}: final: expected an arrangement object")
    request = data.get("request")
    if request is not None and not isinstance(request, str):
        raise BadInput(f"{path}: request: expected a string, got {request!r}")
    return final, request, f"{path}: final"


@click.command(epilog=EPILOG)
@VERBOSE
@click.argument("file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--request", "request_text",
              help="The request the arrangement answers (default: the file's `request`).")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Write the rating (score, summary, every check) as JSON here.")
@click.option("--catalog", "catalog_files", multiple=True,
              type=click.Path(dir_okay=False, path_type=Path),
              help="An extra object catalog file (repeatable).")
def rate(file: Path, request_text: str | None, json_path: Path | None,
         catalog_files: tuple[Path, ...]) -> None:
    """Rate the arrangement in FILE from 1 to 5 as the paper's raters did (Table III).

    FILE is an arrangement JSON (`llm-grop arrange --json`, or any system's output
    in the same shape) or a run JSON (`llm-grop run --json`; its `final` is rated).
    """
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table as RichTable

    from llm_grop.evaluation.rater import rate as rate_arrangement
    from llm_grop.files.jsonio import write_json
    from llm_grop.language.request import parse_request
    from llm_grop.world.catalog import Catalog

    arrangement, run_request, where = read_rating_input(file)
    catalog = Catalog.load(catalog_files)
    text = request_text if request_text is not None else run_request
    requested = None
    if text is not None:
        requested = [item.name for item in parse_request(text, catalog).items]
    rating = rate_arrangement(arrangement, requested, catalog, where=where)

    out = Console()
    colour = {5: "green", 4: "green", 3: "yellow"}.get(rating.score, "red")
    out.print(f"[bold]Score:[/bold] [{colour}]{rating.score}/5[/{colour}]  "
              f"{escape(rating.summary.split(': ', 1)[1])}")
    table = RichTable(title=f"Checks of {escape(str(file))}", title_justify="left")
    for col in ("check", "result", "severity", "detail"):
        table.add_column(col)
    for c in rating.checks:
        result = "[dim]skipped[/dim]" if c.skipped else \
            "[green]passed[/green]" if c.passed else "[red]FAILED[/red]"
        severity = c.severity if not c.passed else f"[dim]{c.severity}[/dim]"
        table.add_row(c.name, result, severity, escape(c.detail))
    out.print(table)
    if json_path is not None:
        write_json(json_path, rating.to_dict())
        out.print(f"Wrote rating JSON: {escape(str(json_path))}")
