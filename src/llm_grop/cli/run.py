"""``llm-grop run``: arrangement, task-motion plan and simulated execution (paper §III-C)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

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
from llm_grop.cli.settings import (
    ARRANGE_FIELDS,
    ATTEMPT_FIELDS,
    LLM_FIELDS,
    ROOM_FIELDS,
    checked_settings,
    flags,
)
from llm_grop.errors import BadInput

if TYPE_CHECKING:
    from llm_grop.settings import RunSettings
    from llm_grop.simulation.base import Simulator


@click.command(epilog=EPILOG)
@VERBOSE
@click.argument("request", required=False)
@flags("task", "scene", "method", "method_options", "seed", "chairs", *ROOM_FIELDS)
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Write the run JSON here.")
@click.option("--image", "image_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Write a picture of the room, the robot's path and the final table here.")
@click.option("--table-image", "table_image", type=click.Path(dir_okay=False, path_type=Path),
              help="3D simulators: write an offscreen render of the final table, from above.")
@click.option("--room-image", "room_image", type=click.Path(dir_okay=False, path_type=Path),
              help="3D simulators: write an offscreen render of the room and the robot.")
@click.option("--video", "video_path", type=click.Path(dir_okay=False, path_type=Path),
              help="--simulator mujoco: write an MP4 video of the episode.")
@click.option("--camera", metavar="NAME",
              help="--simulator mujoco: the camera of --table-image and --video: top-down, "
                   "diner, robot or room [default: top-down for the table render, room for "
                   "the video].")
@flags("rerun", "mcap")
@flags(*ATTEMPT_FIELDS, *LLM_FIELDS)
@RECORD
@flags(*ARRANGE_FIELDS, "cache")
@NO_CACHE
@flags("guess")
@QUIET
def run(request: str | None, json_path: Path | None, image_path: Path | None,
        table_image: Path | None, room_image: Path | None, video_path: Path | None,
        camera: str | None, record_path: Path | None, quiet: bool, no_cache: bool,
        **params: Any) -> None:
    """Set the table in a simulated dining room: arrange, plan, execute (paper §III-C)."""
    from rich.console import Console

    from llm_grop.api import run as api_run
    from llm_grop.assembly import check_recordings
    from llm_grop.cli.console import print_run
    from llm_grop.contract.run_json import run_to_dict
    from llm_grop.files.jsonio import write_json

    check_request("run", request, params["task"])
    settings = checked_settings(params, cache=cache_setting(params["cache"], no_cache))
    # Every output is checked before the LLM is paid for or any planning is done.
    rerun_path: Path | None = params["rerun"]
    mcap_path: Path | None = params["mcap"]
    check_outputs(json=json_path, image=image_path, table_image=table_image,
                  room_image=room_image, video=video_path, record=record_path,
                  rerun=rerun_path, mcap=mcap_path)
    check_recordings(settings)
    if camera is not None and not (table_image or video_path):
        raise BadInput("--camera: needs --table-image or --video (--room-image always "
                       "uses the room camera)")
    err = Console(stderr=True)
    with StagedOutputs() as outputs:
        # The video is recorded beside its place and moved there with the other outputs.
        video_tmp = outputs.path("video", video_path) if video_path is not None else None
        sim = _simulator(settings, table_image or room_image or video_path, video_tmp,
                         camera)
        if rerun_path is not None:
            # Recorded beside its place too, and moved there with the other outputs.
            settings = settings.with_values(rerun=str(outputs.path("rerun", rerun_path)))
        if mcap_path is not None:
            settings = settings.with_values(mcap=str(outputs.path("mcap", mcap_path)))
        with err.status("starting", spinner="dots") as status:
            def on_event(message: str) -> None:
                if not quiet:
                    status.update(message)

            result = api_run(request, settings, simulator=sim, on_event=on_event,
                             record=record_path)
        outputs.write("json", json_path, lambda p: write_json(p, run_to_dict(result)))
        if image_path is not None:
            from llm_grop.render.room import draw_run

            outputs.write("image", image_path, lambda p: draw_run(result, p))
        for flag, view, path in (("table_image", "table", table_image),
                                 ("room_image", "room", room_image)):
            if path is not None:
                from llm_grop.render.raster import save_rgb_png

                picture = sim.picture(view)  # type: ignore[union-attr]
                outputs.write(flag, path, lambda p, image=picture: save_rgb_png(image, p))
        outputs.commit()
    if not quiet:
        out = Console()
        print_run(result, out, err)
        for label, path in (("run JSON", json_path), ("picture", image_path),
                            ("table render", table_image), ("room render", room_image),
                            ("video", video_path), ("recording", rerun_path),
                            ("ROS 2 bag", mcap_path)):
            if path is not None:
                out.print(f"Wrote {label}: {path}")


def _simulator(settings: RunSettings, pictures: object, video: Path | None,
               camera: str | None = None) -> Simulator | None:
    """The simulator to run (``None``: the one the settings name, made by the API); with
    pictures or a video it must declare that it makes them, from ``camera`` among its
    cameras, and rendering is checked before any work."""
    from llm_grop.assembly import make_simulator
    from llm_grop.simulation.registry import simulator_class

    cls = simulator_class(settings.simulator)
    if camera is not None and camera not in cls.cameras:
        named = f"choose from {', '.join(cls.cameras)}" if cls.cameras else \
            f"simulator {settings.simulator!r} has no cameras"
        raise BadInput(f"unknown camera {camera!r}; {named}", param="camera")
    if not pictures:
        return None
    if not cls.supports_pictures or video is not None and not cls.supports_video:
        flag = "--video" if video else "--table-image/--room-image"
        raise BadInput(f"{flag}: needs a simulator that renders, such as --simulator mujoco "
                       f"(got {settings.simulator!r})")
    made = settings.with_values(sim_options=dict(settings.sim_options) | {
        "video_path": str(video) if video else None, "camera": camera})
    sim = make_simulator(made)
    sim.check_rendering()
    return sim
