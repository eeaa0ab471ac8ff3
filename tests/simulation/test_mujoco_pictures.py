"""The MuJoCo pictures raters judge: tableware with recognisable shapes (a fork's tines, a
knife's blade, a round plate), each in its kind's colour of the 2D pictures, a placemat
at each diner's seat, and named cameras for the table render and the video."""

from __future__ import annotations

import math
from itertools import combinations
from pathlib import Path

import imageio_ffmpeg
import numpy as np
import pytest
from PIL import Image

from cli_support import one_line_error
from llm_grop.cli import main
from llm_grop.planning.navigation import Navigator
from llm_grop.render.table import kind_color
from llm_grop.simulation.mujoco.looks import GROUP_COLLISION, GROUP_VISUAL, lathe
from llm_grop.simulation.mujoco.options import CAMERAS, MujocoOptions
from llm_grop.simulation.mujoco.session import MujocoSession
from llm_grop.simulation.mujoco.simulator import MujocoSimulator
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Box, Pose2D
from llm_grop.world.kind_colors import kind_rgb
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import ObjectSource, Scene, SceneTable
from llm_grop.world.seat import Seat

SETTING = (("dinner plate", 0.0, 0.0), ("dinner fork", -0.18, 0.0),
           ("dinner knife", 0.18, 0.0), ("mug mat", 0.30, 0.17), ("mug", 0.30, 0.17))


def _session(objects: tuple[tuple[str, float, float], ...], table: tuple[float, float],
             options: MujocoOptions | None = None, diners: tuple[Seat, ...] = ()
             ) -> tuple[MujocoSimulator, MujocoSession]:
    """A 3 x 3 m room whose one table (``table``: width, depth, metres, centred at
    (1.5, 1.5)) holds ``objects`` (kind, table-frame x, y), settled."""
    scene = Scene(name="picture room", width=3.0, depth=3.0,
                  tables=(SceneTable("table", Box(1.5, 1.5, *table)),), target="table",
                  robot_start=Pose2D(0.4, 0.4, 0.0), source_tables=("table",),
                  sources=tuple(ObjectSource(n, "table", 1.5 + x, 1.5 + y)
                                for n, x, y in objects),
                  chairs_listed=True, diners=diners)
    sim = MujocoSimulator(options)
    session = sim.session(scene, items_from_names([n for n, *_ in objects], Catalog.load()),
                          np.random.default_rng(0),
                          replan=Navigator(scene, scene.robot.base_radius_m))
    return sim, session


def _mask(image: np.ndarray) -> np.ndarray:
    """Where a coloured object is: saturated pixels (the cloth and the floor are greyish)."""
    rgb = image.astype(int)
    return rgb.max(axis=2) - rgb.min(axis=2) > 50


def _alone(kind: str) -> np.ndarray:
    """``kind`` alone on a 0.32 m square table, from above (0.77 mm a pixel), as a mask."""
    _, s = _session(((kind, 0.0, 0.0),), (0.32, 0.32))
    return _mask(s.picture("table", camera="top-down"))


def _runs(row: np.ndarray) -> int:
    """Separate stretches of True in ``row``."""
    return int(np.count_nonzero(np.diff(np.concatenate([[0], row.astype(int), [0]])) == 1))


def test_fork_and_knife_differ_by_their_pixels() -> None:
    fork, knife = _alone("dinner fork"), _alone("dinner knife")
    assert fork.sum() > 500 and knife.sum() > 500
    # A row across the fork's far end crosses four tines; no row crosses a knife twice.
    fork_runs = [_runs(r) for r in fork]
    knife_runs = [_runs(r) for r in knife]
    assert sum(n >= 4 for n in fork_runs) >= 10
    assert max(knife_runs) == 1
    # The tines are at the top of the picture (+y, away from the diner) ...
    fork_rows = np.flatnonzero(fork.any(axis=1))
    tine_rows = [k for k, n in enumerate(fork_runs) if n >= 4]
    assert np.mean(tine_rows) < np.mean(fork_rows)
    # ... and end square, where the knife's blade ends in a rounded tip.
    fork_widths = fork.sum(axis=1)[fork_rows]
    knife_widths = knife.sum(axis=1)[knife.any(axis=1)]
    assert fork_widths[0] > 0.5 * fork_widths.max()
    assert knife_widths[0] < 0.25 * knife_widths.max()


def test_a_plate_is_round() -> None:
    plate = _alone("dinner plate")
    ys, xs = np.nonzero(plate)
    cy, cx = ys.mean(), xs.mean()
    radii = []
    for a in np.radians(np.arange(0, 360, 2)):
        r = 0.0
        while plate[int(round(cy + r * math.sin(a))), int(round(cx + r * math.cos(a)))]:
            r += 0.25
        radii.append(r)
    # A 12-sided polygon's radius varies by 3.4 %; a circle's only by the pixels'.
    assert (max(radii) - min(radii)) / np.mean(radii) < 0.015
    assert 150 < np.mean(radii) < 200  # 0.135 m at 0.77 mm a pixel


def test_a_lathe_mesh_is_closed_and_faces_out() -> None:
    v, f = lathe([(0, 0), (1, 0), (1, 1), (0, 1)], 64)
    edges = {}
    for tri in f:
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            edges[(a, b)] = edges.get((a, b), 0) + 1
    assert all(edges.get((b, a)) == 1 for a, b in edges)  # every edge shared, once each way
    volume = np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6
    assert volume == pytest.approx(math.pi, rel=0.01)  # a unit cylinder, wound outwards


def test_each_object_is_drawn_in_its_kinds_colour_of_the_2d_pictures() -> None:
    sim, s = _session(SETTING, (0.9, 0.6))
    m = s.w.m
    for name, *_ in SETTING:
        # The 2D pictures and the renders read one list of colours.
        assert kind_color(name) == "#" + "".join(f"{round(c * 255):02x}" for c in kind_rgb(name))
        body = m.body(name).id
        geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] == body]
        drawn = [g for g in geoms if m.geom_group[g] == GROUP_VISUAL]
        hidden = [g for g in geoms if m.geom_group[g] == GROUP_COLLISION]
        # A look is drawn and never collides; the collision geoms behind it are hidden.
        assert drawn and hidden
        assert all(m.geom_contype[g] == 0 == m.geom_conaffinity[g] for g in drawn)
        assert all(m.geom_contype[g] != 0 for g in hidden)
        for g in drawn:
            assert tuple(m.geom_rgba[g][:3]) == pytest.approx(kind_rgb(name), abs=1e-6)
    # In the picture from above, each object shows in its own colour: the median of a few
    # pixels at its centre (table frame -> pixels: the orthographic view of a 0.9 x 0.6 m
    # table is 0.9 * 3/4 * 1.15 m high, its centre the table's).
    image = sim.picture("table", (640, 480))
    metres_per_pixel = 0.9 * 0.75 * 1.15 / 480
    for name, x, y in SETTING:
        if name == "mug mat":
            continue  # under the mug: test_the_mug_mat_shows_round_the_mug
        col, row = round(320 + x / metres_per_pixel), round(240 - y / metres_per_pixel)
        seen = np.median(image[row - 2:row + 3, col - 2:col + 3].reshape(-1, 3), axis=0)
        assert np.linalg.norm(seen - np.array(kind_rgb(name)) * 255) < 20, (name, seen)


def test_the_mug_mat_shows_round_the_mug() -> None:
    _, s = _session((("mug mat", 0.0, 0.0), ("mug", 0.0, 0.0)), (0.32, 0.32))
    image = s.picture("table").astype(float)
    mat = np.linalg.norm(image - np.array(kind_rgb("mug mat")) * 255, axis=2) < 40
    # A ring of the mat's colour, about 1 cm wide round the 9 cm mug, is in sight.
    assert mat.sum() > 1000
    assert s.objects()["mug"].on == "mug mat"


def test_a_placemat_marks_each_diners_seat() -> None:
    diners = (Seat(0.0, -0.45, math.pi / 2), Seat(0.0, 0.45, -math.pi / 2))
    _, s = _session((("dinner plate", 0.0, -0.2),), (1.2, 0.9), diners=diners)
    m = s.w.m
    mats = [m.geom(f"placemat:{k}") for k in range(2)]
    ys = sorted(float(g.pos[1]) for g in mats)
    # One mat at each seat's edge, inside the top; drawn only, so nothing stands on it.
    assert ys[0] < 1.5 - 0.2 and ys[1] > 1.5 + 0.2
    assert all(g.contype[0] == 0 == g.conaffinity[0] for g in mats)
    assert s.objects()["dinner plate"].z == pytest.approx(0.75, abs=0.003)


def test_each_camera_gives_its_own_picture() -> None:
    sim, s = _session(SETTING, (0.9, 0.6))
    pictures = {c: sim.picture("table", (160, 120), camera=c).astype(float) for c in CAMERAS}
    for a, b in combinations(CAMERAS, 2):
        assert np.abs(pictures[a] - pictures[b]).mean() > 10, (a, b)
    # The default table picture is the top-down one; the option chooses another.
    assert np.array_equal(sim.picture("table", (160, 120)), pictures["top-down"])
    sim.options = MujocoOptions(camera="diner")
    assert np.array_equal(sim.picture("table", (160, 120)), pictures["diner"])


def test_the_video_is_filmed_from_the_chosen_camera(tmp_path: Path) -> None:
    video = tmp_path / "v.mp4"
    sim, s = _session(SETTING, (0.9, 0.6), MujocoOptions(video_path=str(video),
                                                         camera="diner"))
    s.w.advance(0.5)
    s.close()
    frames = imageio_ffmpeg.read_frames(str(video))
    meta = next(frames)
    last = None
    for raw in frames:
        last = np.frombuffer(raw, np.uint8).reshape(meta["size"][1], meta["size"][0], 3)
    assert last is not None
    diner = s.picture("room", camera="diner").astype(float)
    room = s.picture("room").astype(float)
    assert np.abs(last - diner).mean() < 5 < np.abs(last - room).mean()


def test_an_unknown_camera_is_refused_in_one_line(capsys, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="unknown camera 'nope'; choose from top-down, "
                                         "diner, robot, room"):
        MujocoOptions(camera="nope")  # type: ignore[arg-type]
    assert main(["run", "a dinner fork", "--method", "grop", "--simulator", "mujoco",
                 "--table-image", str(tmp_path / "t.png"), "--camera", "nope"]) == 2
    line = one_line_error(capsys)
    assert "camera" in line and "'nope'" in line and "top-down, diner, robot, room" in line
    for alone in ([], ["--simulator", "mujoco", "--room-image", str(tmp_path / "r.png")]):
        assert main(["run", "a dinner fork", "--method", "grop", *alone,
                     "--camera", "diner"]) == 2
        assert "--camera: needs --table-image or --video" in one_line_error(capsys)
    assert not (tmp_path / "r.png").exists()
    assert not (tmp_path / "t.png").exists()


def test_run_renders_the_table_from_the_chosen_camera(tmp_path: Path) -> None:
    table, room = tmp_path / "table.png", tmp_path / "room.png"
    assert main(["run", "a dinner fork", "--method", "grop", "--chairs", "0",
                 "--simulator", "mujoco", "--camera", "room", "--table-image", str(table),
                 "--room-image", str(room), "-q"]) == 0
    # From one camera the table render and the room render differ only by the robot,
    # which the table render hides.
    a = np.asarray(Image.open(table)).astype(float)
    b = np.asarray(Image.open(room)).astype(float)
    changed = np.abs(a - b).max(axis=2) > 30
    assert 0 < changed.mean() < 0.1
