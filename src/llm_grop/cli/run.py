"""``llm-grop run``: arrangement, task-motion plan and simulated execution (paper §III-C)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from llm_grop.cli.execution import cache_flags, cache_setting
from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import (
    EPILOG,
    FEASIBILITY,
    FIDELITY_WEIGHT,
    GRASP,
    NO_GUESS,
    SIMULATOR,
    TABLE,
    TRUTH,
    WEIGHT,
    StagedOutputs,
    attempt_flags,
    check_outputs,
    check_request,
    llm_flags,
    llm_settings,
)
from llm_grop.errors import BadInput
from llm_grop.world.table import Table


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
@TABLE
@SIMULATOR
@GRASP
@TRUTH
@FEASIBILITY
@WEIGHT
@FIDELITY_WEIGHT
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
@attempt_flags
@llm_flags
@cache_flags
@NO_GUESS
@click.option("-q", "--quiet", is_flag=True, help="Print nothing but errors.")
def run(request: str | None, task: int | None, scene_path: Path | None, method: str, seed: int,
        chairs: int | None, table: Table | None, simulator: str, grasp: str,
        truth: str | None, feasibility: str, w: float, fidelity_w: float,
        json_path: Path | None,
        image_path: Path | None, table_image: Path | None, room_image: Path | None,
        video_path: Path | None, camera: str | None, record_path: Path | None,
        catalog_files: tuple[Path, ...],
        quiet: bool, no_guess: bool, nav_attempts: int, manip_attempts: int | None,
        cache_dir: Path | None, no_cache: bool, **flags: Any) -> None:
    """Set the table in a simulated dining room: arrange, plan, execute (paper §III-C)."""
    from rich.console import Console

    from llm_grop.api import run as api_run
    from llm_grop.cli.console import print_run
    from llm_grop.execution import ExecutionPolicy
    from llm_grop.planning.utility import GropOptions
    from llm_grop.world.jsonio import write_json
    from llm_grop.world.run_json import run_to_dict

    check_request("run", request, task)
    llm_options, options = llm_settings(**flags)
    # Every output is checked before the LLM is paid for or any planning is done.
    check_outputs(json=json_path, image=image_path, table_image=table_image,
                  room_image=room_image, video=video_path, record=record_path)
    if camera is not None and not (table_image or video_path):
        raise BadInput("--camera: needs --table-image or --video (--room-image always "
                       "uses the room camera)")
    cache = cache_setting(cache_dir, no_cache)
    err = Console(stderr=True)
    with StagedOutputs() as outputs:
        # The video is recorded beside its place and moved there with the other outputs.
        video_tmp = outputs.path("video", video_path) if video_path is not None else None
        sim = _simulator(simulator, table_image or room_image or video_path, video_tmp,
                         grasp, truth, camera)
        with err.status("starting", spinner="dots") as status:
            def on_event(message: str) -> None:
                if not quiet:
                    status.update(message)

            result = api_run(request, task=task, method=method, scene=scene_path,
                             chairs=chairs, table=table, seed=seed, llm=flags["backend"],
                             llm_options=llm_options, catalog_files=catalog_files,
                             options=options, record=record_path,
                             planner=GropOptions(w=w, fidelity_w_s_per_cm=fidelity_w),
                             simulator=sim, feasibility=feasibility,
                             on_event=on_event, guess=not no_guess, cache=cache,
                             execution=ExecutionPolicy(nav_attempts=nav_attempts,
                                                       manip_attempts=manip_attempts))
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
                            ("video", video_path)):
            if path is not None:
                out.print(f"Wrote {label}: {path}")


def _simulator(name: str, pictures: object, video: Path | None, grasp: str = "fix",
               truth: str | None = None, camera: str | None = None) -> Any:
    """The simulator to run: ``name`` from the registry, holding with ``grasp`` (MuJoCo)
    or drawing from ``truth`` (2D); with pictures or a video it must render (MuJoCo) from
    ``camera``, and rendering is checked before any work."""
    from llm_grop.simulation.registry import SIMULATORS, create_simulator

    if camera is not None:
        from llm_grop.simulation.mujoco.options import check_camera

        check_camera(camera)
    if not pictures or truth is not None:
        if grasp == "fix" and truth is None:
            return name
        sim = create_simulator(name, grasp=grasp, truth=truth)
        if pictures:
            raise BadInput("--table-image/--room-image/--video: need --simulator mujoco "
                           f"(got {name!r})")
        return sim
    if SIMULATORS.key(name) != "mujoco":
        flag = "--video" if video else "--table-image/--room-image"
        raise BadInput(f"{flag}: needs --simulator mujoco (got {name!r})")
    from llm_grop.simulation.mujoco.render import check_rendering, check_video_path
    from llm_grop.simulation.mujoco.simulator import MujocoOptions, MujocoSimulator

    if video is not None:
        check_video_path(video)
    check_rendering()
    return MujocoSimulator(MujocoOptions(video_path=str(video) if video else None,
                                         grasp=grasp,  # type: ignore[arg-type]
                                         camera=camera))  # type: ignore[arg-type]
