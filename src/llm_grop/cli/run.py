"""``llm-grop run``: arrangement, task-motion plan and simulated execution (paper §III-C)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG, SIMULATOR, check_request, llm_flags, llm_settings


@click.command(epilog=EPILOG)
@VERBOSE
@click.argument("request", required=False)
@click.option("--task", type=click.IntRange(1),
              help="Use the objects of the paper's Table I task N.")
@click.option("--scene", "scene_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Dining-room scene YAML (default: the packaged dining room).")
@click.option("--method", default="llm-grop", show_default=True,
              help="tpra, latp, grop, llm-grop, or a plugin's (see `llm-grop plugins`).")
@click.option("--seed", default=0, show_default=True, type=click.IntRange(0),
              help="Seed for the scene's chairs, the LLM, the sampler, the plan and execution.")
@click.option("--chairs", type=click.IntRange(0),
              help="Chairs to sample near the table [default: the scene's own, else 1].")
@SIMULATOR
@click.option("--weight", "w", default=40.0, show_default=True, type=click.FloatRange(0),
              help="GROP's utility weight w (seconds per unit of success probability).")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Write the run JSON here.")
@click.option("--image", "image_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Write a picture of the room, the robot's path and the final table here.")
@llm_flags
@click.option("-q", "--quiet", is_flag=True, help="Print nothing but errors.")
def run(request: str | None, task: int | None, scene_path: Path | None, method: str, seed: int,
        chairs: int | None, simulator: str, w: float, json_path: Path | None,
        image_path: Path | None, record_path: Path | None, catalog_files: tuple[Path, ...],
        quiet: bool, **flags: Any) -> None:
    """Set the table in a simulated dining room: arrange, plan, execute (paper §III-C)."""
    from rich.console import Console

    from llm_grop.api import run as api_run
    from llm_grop.cli.console import print_run
    from llm_grop.planning.utility import GropOptions
    from llm_grop.world.jsonio import write_json
    from llm_grop.world.run_json import run_to_dict

    check_request("run", request, task)
    llm_options, options = llm_settings(**flags)
    err = Console(stderr=True)
    with err.status("starting", spinner="dots") as status:
        def on_event(message: str) -> None:
            if not quiet:
                status.update(message)

        result = api_run(request, task=task, method=method, scene=scene_path, chairs=chairs,
                         seed=seed, llm=flags["backend"], llm_options=llm_options,
                         catalog_files=catalog_files, options=options, record=record_path,
                         planner=GropOptions(w=w), simulator=simulator, on_event=on_event)
    if json_path is not None:
        write_json(json_path, run_to_dict(result))
    if image_path is not None:
        from llm_grop.render.room import draw_run

        draw_run(result, image_path)
    if not quiet:
        out = Console()
        print_run(result, out)
        for label, path in (("run JSON", json_path), ("picture", image_path)):
            if path is not None:
                out.print(f"Wrote {label}: {path}")
