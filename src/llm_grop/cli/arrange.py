"""``llm-grop arrange``: the semantic arrangement alone (paper §III-A, §III-B)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from llm_grop.cli.execution import NO_CACHE, cache_setting
from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import (
    EPILOG,
    QUIET,
    RECORD,
    StagedOutputs,
    check_outputs,
    check_request,
)
from llm_grop.cli.settings import ARRANGE_FIELDS, LLM_FIELDS, checked_settings, flags


@click.command(epilog=EPILOG)
@VERBOSE
@click.argument("request", required=False)
@flags("task", "table", "diners", "seed", help={"seed": "Seed for every LLM call and the sampler."})
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Write the arrangement JSON here.")
@click.option("--image", "image_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Write a top-down PNG of the table here.")
@flags(*LLM_FIELDS)
@RECORD
@flags(*ARRANGE_FIELDS, "cache")
@NO_CACHE
@flags("guess")
@QUIET
def arrange(request: str | None, json_path: Path | None, image_path: Path | None,
            record_path: Path | None, quiet: bool, no_cache: bool, **params: Any) -> None:
    """Arrange the objects of REQUEST on the table (paper §III-A, §III-B).

    REQUEST is in your own words ("a plate with a fork on its left", "breakfast for
    two"): the catalog matcher reads it when it knows every word, else the LLM reads it.
    """
    from rich.console import Console

    from llm_grop.api import arrange as api_arrange
    from llm_grop.contract.serialize import arrangement_to_dict
    from llm_grop.files.jsonio import write_json

    check_request("arrange", request, params["task"])
    settings = checked_settings(params, cache=cache_setting(params["cache"], no_cache))
    # Every output is checked before the LLM is paid for.
    check_outputs(json=json_path, image=image_path, record=record_path)
    out = Console()
    err = Console(stderr=True)
    with err.status("starting", spinner="dots") as status:
        def on_event(message: str) -> None:
            if not quiet:
                status.update(message)

        result = api_arrange(request, settings, record=record_path, on_event=on_event)
    with StagedOutputs() as outputs:
        outputs.write("json", json_path,
                      lambda p: write_json(p, arrangement_to_dict(result.arrangement)))
        if image_path is not None:
            from llm_grop.render.table import draw_arrangement

            outputs.write("image", image_path,
                          lambda p: draw_arrangement(result.arrangement, p))
        outputs.commit()
    if not quiet:
        from llm_grop.cli.console import print_arrangement

        print_arrangement(result, out, err)
        for label, path in (("arrangement JSON", json_path), ("picture", image_path)):
            if path is not None:
                out.print(f"Wrote {label}: {path}")
