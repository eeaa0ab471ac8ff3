"""``llm-grop arrange``: the semantic arrangement alone (paper §III-A, §III-B)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from llm_grop.cli.execution import cache_flags, cache_setting
from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import (
    EPILOG,
    NO_GUESS,
    TABLE,
    StagedOutputs,
    check_outputs,
    check_request,
    llm_flags,
    llm_settings,
)
from llm_grop.world.table import Table


@click.command(epilog=EPILOG)
@VERBOSE
@click.argument("request", required=False)
@click.option("--task", type=click.IntRange(1),
              help="Use the objects of the paper's Table I task N.")
@TABLE
@click.option("--seed", default=0, show_default=True, type=click.IntRange(0),
              help="Seed for every LLM call and the sampler.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Write the arrangement JSON here.")
@click.option("--image", "image_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Write a top-down PNG of the table here.")
@llm_flags
@cache_flags
@NO_GUESS
@click.option("-q", "--quiet", is_flag=True, help="Print nothing but errors.")
def arrange(request: str | None, task: int | None, table: Table | None, seed: int,
            json_path: Path | None, image_path: Path | None, record_path: Path | None,
            catalog_files: tuple[Path, ...], quiet: bool, no_guess: bool,
            cache_dir: Path | None, no_cache: bool, **flags: Any) -> None:
    """Arrange the objects of REQUEST on the table (paper §III-A, §III-B).

    REQUEST is in your own words ("a plate with a fork on its left", "breakfast for
    two"): the catalog matcher reads it when it knows every word, else the LLM reads it.
    """
    from rich.console import Console

    from llm_grop.api import arrange as api_arrange
    from llm_grop.world.jsonio import write_json
    from llm_grop.world.serialize import arrangement_to_dict

    check_request("arrange", request, task)
    llm_options, options = llm_settings(**flags)
    # Every output is checked before the LLM is paid for.
    check_outputs(json=json_path, image=image_path, record=record_path)
    cache = cache_setting(cache_dir, no_cache)
    out = Console()
    err = Console(stderr=True)
    with err.status("starting", spinner="dots") as status:
        def on_event(message: str) -> None:
            if not quiet:
                status.update(message)

        result = api_arrange(request, task=task, llm=flags["backend"], llm_options=llm_options,
                             table=table if table is not None else Table(), seed=seed,
                             catalog_files=catalog_files, options=options, record=record_path,
                             on_event=on_event, guess=not no_guess, cache=cache)
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
