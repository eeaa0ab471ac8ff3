"""Rendering time per 3D frame (MuJoCo, offscreen), milliseconds, for each named camera.

Builds the packaged dining room with a typical 3-object place setting (dinner plate, fork,
knife) and a 6-object one (and a spoon, a mug on its mat) on the target table, lets it
settle, then renders N frames of 640 x 480 pixels from each camera with one open renderer
(as a video does) and prints the mean and the minimum per frame. A few frames are rendered
first and not counted (GL warm-up).

It uses only what the simulator offered before named cameras existed, so it also measures
an older checkout: run it with ``PYTHONPATH=<old tree>/src`` and it times the two views
that tree has, ``table`` (the top-down table render) and ``room`` (the video's overview).
Run: MUJOCO_GL=osmesa .venv/bin/python benchmarks/render_3d.py [--frames N] [--quick]
"""

from __future__ import annotations

import argparse
import inspect
import statistics
import time
from pathlib import Path

import numpy as np
from common import parse_args
from PIL import Image

from llm_grop.files.scene_file import load_scene
from llm_grop.planning.navigation import Navigator
from llm_grop.simulation.mujoco import options, render
from llm_grop.simulation.mujoco.simulator import MujocoOptions, MujocoSimulator
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import ObjectSource

#: Place settings, table frame (metres; +y away from the diner).
SETTINGS = {
    "3 objects": (("dinner plate", 0.0, 0.0), ("dinner fork", -0.18, 0.0),
                  ("dinner knife", 0.18, 0.0)),
    "6 objects": (("dinner plate", 0.0, 0.0), ("dinner fork", -0.18, 0.0),
                  ("dinner knife", 0.18, 0.0), ("soup spoon", 0.23, 0.0),
                  ("mug mat", 0.30, 0.17), ("mug", 0.30, 0.17)),
}
SIZE = (640, 480)
WARM_UP = 3


def _world(setting: tuple[tuple[str, float, float], ...]):  # noqa: ANN202 - a World
    """The packaged dining room with ``setting`` on its target table, settled."""
    scene = load_scene()
    sources = []
    for name, x, y in setting:
        p = scene.table_to_room(x, y)
        sources.append(ObjectSource(name, scene.target, p.x, p.y))
    scene = scene.with_sources(tuple(sources))
    names = [name for name, *_ in setting]
    sim = MujocoSimulator(MujocoOptions(image_size=SIZE))
    session = sim.session(scene, items_from_names(names, Catalog.load()),
                          np.random.default_rng(0),
                          replan=Navigator(scene, scene.robot.base_radius_m))
    session.close()
    return sim.world


def _views() -> list[tuple[str, dict[str, str]]]:
    """(label, render_with keywords) for each camera the installed simulator has."""
    cameras = getattr(options, "CAMERAS", None)
    if cameras is None or "camera" not in inspect.signature(render.render_with).parameters:
        return [("top-down", {"view": "table"}), ("room", {"view": "room"})]
    # Each camera as its picture is made: top-down as the table render (robot hidden),
    # the others as a video's frames (robot drawn).
    return [(name, {"view": "table" if name == "top-down" else "room", "camera": name})
            for name in cameras]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=30, help="frames timed per camera")
    parser.add_argument("--save", type=Path, help="also write each camera's frame here (PNG)")
    args = parse_args(parser, {"frames": 1})
    print(f"{SIZE[0]}x{SIZE[1]} pixels, mean (min) ms per frame over {args.frames} frames")
    for label, setting in SETTINGS.items():
        world = _world(setting)
        renderer = render.new_renderer(world.m, SIZE)
        try:
            parts = []
            for camera, kw in _views():
                for _ in range(WARM_UP):
                    render.render_with(renderer, world, **kw)
                times = []
                for _ in range(args.frames):
                    t0 = time.perf_counter()
                    render.render_with(renderer, world, **kw)
                    times.append((time.perf_counter() - t0) * 1000)
                if args.save is not None:
                    image = render.render_with(renderer, world, **kw)
                    args.save.mkdir(parents=True, exist_ok=True)
                    Image.fromarray(image).save(args.save / f"{label[0]}-{camera}.png")
                parts.append(f"{camera} {statistics.fmean(times):.1f} ({min(times):.1f})")
        finally:
            renderer.close()
        print(f"{label}: {world.m.ngeom} geoms; " + ", ".join(parts))


if __name__ == "__main__":
    main()
