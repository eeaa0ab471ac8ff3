"""``llm-grop rate``: the automatic 1-5 rating of an arrangement JSON (paper Table III)."""

from __future__ import annotations

from pathlib import Path

import click

from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG


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

    from llm_grop.contract.serialize import read_arrangement_file
    from llm_grop.evaluation.rater import rate as rate_arrangement
    from llm_grop.files.jsonio import write_json
    from llm_grop.language.request import parse_request
    from llm_grop.world.catalog import Catalog

    arrangement, run_request, where = read_arrangement_file(file)
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
