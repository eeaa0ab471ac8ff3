"""The dining room as a MuJoCo model, built from the scene with MuJoCo's model editor.

The robot comes from ``assets/robot.xml`` (with the tray of ``world/tray.xml`` on its
base when it carries several objects per trip); floor, walls, tables with legs (a round one: a
cylinder top on a pedestal), chairs with seat, back and legs, a placemat in front of each
diner's seat (drawn only), and the tableware, each in its kind's colour, are added around
it, with the named cameras (:data:`~llm_grop.simulation.mujoco.options.CAMERAS`). World
frame = the scene's room frame (metres, radians), z up from the floor. Furniture is fixed
to the world; tableware bodies are free, each with an inactive weld to the hand that a
grasp switches on (see :mod:`llm_grop.simulation.mujoco.manipulation`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources

import mujoco
import numpy as np
from shapely.affinity import rotate, translate
from shapely.geometry import LineString, Point, Polygon
from shapely.geometry import box as rectangle

from llm_grop.errors import BadInput
from llm_grop.simulation.mujoco.cameras import add_cameras
from llm_grop.simulation.mujoco.looks import (
    GROUP_COLLISION,
    GROUP_VISUAL,
    Visual,
    add_look,
    lathe,
)
from llm_grop.simulation.mujoco.tableware import Tableware, add_body
from llm_grop.world.geometry2d import Box, Disc
from llm_grop.world.kind_colors import TABLE_TOP, hex_rgb, kind_rgb
from llm_grop.world.scene import Chair, Scene, SceneTable
from llm_grop.world.tray import tray_xml_path

#: Furniture collision bits (robot.xml): collides with the robot (2) and tableware (4).
FURNITURE = (1, 2 | 4)
#: Chair collision bits: like furniture, and also with other furniture (1) and the floor
#: (16), since a chair is pushed across the floor and into tables and walls.
CHAIR = (1 | 16, 1 | 2 | 4)
#: Floor collision bits: tableware and chairs stand on it.
FLOOR = (8, 4 | 16)
#: Shares of a chair's mass: seat, back, and each of four legs.
CHAIR_MASS_SHARES = (0.4, 0.3, 0.075)
#: Height of the outer and interior walls, metres (low, so the overview sees in).
WALL_HEIGHT_M = 1.0
#: Chairs: seat height, seat thickness, back height (metres).
SEAT_Z_M, SEAT_T_M, BACK_TOP_M = 0.45, 0.04, 0.90
#: Thickness of a table top and side of a square leg, metres.
TOP_T_M, LEG_M = 0.03, 0.05
#: A round table's pedestal: radius and thickness of its foot, metres (the column's
#: radius is ``LEG_M``).
PEDESTAL_FOOT_M, FOOT_T_M = 0.25, 0.03
#: Geom group of furniture and tableware in renders (robot.xml draws the robot in 2).
GROUP_WORLD = 0
#: Facets round a round table's top as drawn.
ROUND_TOP_FACETS = 96
#: A diner's placemat: width along the table's edge, depth into the table, thickness, and
#: its gap to the edge (metres). It is drawn only: objects stand on the table top through
#: it.
PLACEMAT_M = (0.45, 0.33, 0.001)
PLACEMAT_GAP_M = 0.015

_WOOD = (0.62, 0.45, 0.30, 1.0)
#: The target table's top: the 2D pictures' cloth.
_TARGET = (*hex_rgb(TABLE_TOP), 1.0)
_PLACEMAT = (0.62, 0.67, 0.73, 1.0)
_CHAIR = (0.35, 0.25, 0.18, 1.0)
_WALL = (0.86, 0.85, 0.82, 1.0)


@dataclass(frozen=True)
class ObjectStart:
    """Where a piece of tableware starts: its bottom centre ``(x, y, z)`` (metres, room
    frame) and ``yaw`` (radians)."""

    item: Tableware
    x: float
    y: float
    z: float
    yaw: float = 0.0


@dataclass(frozen=True)
class WorldModel:
    """A compiled dining room and the indices the simulator looks things up by.

    Attributes:
        model: the MuJoCo model.
        objects: tableware by name.
        furniture: per geom, whether it is furniture (tables, chairs, walls).
        robot: per geom, whether it belongs to the robot.
        arm: per geom, whether it belongs to the arm or the gripper.
        fingers: per geom, whether it is a finger or pad (they may touch a table top).
        owner: per geom, the tableware it belongs to ("" for none).
        parts: tableware name -> per geom, whether the geom is part of it.
        tops: table name -> geom id of its top; :data:`TRAY_TOP` -> the tray's top, when
            the robot has one.
        welds: tableware name -> id of its grasp weld.
        chairs: chair name -> body id.
    """

    model: mujoco.MjModel
    objects: dict[str, Tableware]
    furniture: np.ndarray
    robot: np.ndarray
    arm: np.ndarray
    fingers: np.ndarray
    owner: tuple[str, ...]
    parts: dict[str, np.ndarray]
    tops: dict[str, int]
    welds: dict[str, int]
    chairs: dict[str, int]


#: The tray's body, the prefix of its names in the model ...
TRAY = "tray"
#: ... and the key of its top in :attr:`WorldModel.tops` (no table's name: a scene's tables
#: have names of words).
TRAY_TOP = "robot's tray"


def robot_xml() -> str:
    """The path of the robot's MJCF file."""
    return str(resources.files("llm_grop.simulation.mujoco").joinpath("assets/robot.xml"))


def tray_xml() -> str:
    """The path of the tray's MJCF file."""
    return str(tray_xml_path())


def check_scene(scene: Scene) -> None:
    """:class:`BadInput` when the scene cannot be built: furniture that interpenetrates or
    leaves the room, or a robot that starts inside something."""
    room = Polygon([(0, 0), (scene.width, 0), (scene.width, scene.depth), (0, scene.depth)])
    parts: list[tuple[str, Box | Disc]] = [(f"table {t.name!r}", t.footprint)
                                           for t in scene.tables]
    parts += [(f"chair {c.name!r}", c.box) for c in scene.chairs]
    parts += [(f"wall {k}", w) for k, w in enumerate(scene.walls)]
    polys = [(label, Polygon(b.outline())) for label, b in parts]
    for label, poly in polys:
        if not label.startswith("wall") and not room.buffer(1e-6).contains(poly):
            raise BadInput(f"scene {scene.name!r}: {label} reaches outside the room")
    for i, (a, pa) in enumerate(polys):
        for b, pb in polys[i + 1:]:
            if pa.intersection(pb).area > 1e-6:
                raise BadInput(f"scene {scene.name!r}: {a} and {b} interpenetrate")
    start = Point(scene.robot_start.x, scene.robot_start.y).buffer(scene.robot.base_radius_m)
    for label, poly in polys:
        if start.intersection(poly).area > 1e-6:
            raise BadInput(f"scene {scene.name!r}: the robot starts inside {label}")


def build(scene: Scene, starts: Sequence[ObjectStart], *, timestep_s: float = 0.004,
          image_size: tuple[int, int] = (640, 480), traction_n: float = 580.0,
          chair_mass_kg: float = 5.0, chair_friction: float = 0.5, tray: bool = False
          ) -> WorldModel:
    """The dining room of ``scene`` with the robot at its start and the tableware at
    ``starts``; the base's wheels transmit at most ``traction_n`` newtons, and chairs
    weigh ``chair_mass_kg`` and slide with friction ``chair_friction``; with ``tray`` the
    base carries the tray. Raises :class:`BadInput` when the scene cannot be built."""
    check_scene(scene)
    spec = mujoco.MjSpec.from_file(robot_xml())
    if tray:
        # Fixed to the base (no joint): it moves with it, and what rides on it rides by
        # friction.
        spec.body("base").add_frame().attach_body(
            mujoco.MjSpec.from_file(tray_xml()).body(TRAY), f"{TRAY}/", "")
    for act in spec.actuators:
        if act.name in ("base_x", "base_y"):
            act.forcerange = [-traction_n, traction_n]
        elif act.name == "base_yaw":
            # Two wheels 0.5 m apart turn the base with their traction at 0.25 m.
            act.forcerange = [-0.25 * traction_n, 0.25 * traction_n]
    spec.modelname = "llm-grop dining room"
    spec.option.timestep = timestep_s
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.visual.global_.offwidth, spec.visual.global_.offheight = image_size
    # Ambient, headlight and sun add up to about 1 on a top face seen from above, so the
    # top-down render shows each kind in its own colour, as the 2D pictures do.
    spec.visual.headlight.ambient = [0.25, 0.25, 0.25]
    spec.visual.headlight.diffuse = [0.30, 0.30, 0.30]
    spec.visual.headlight.specular = [0.05, 0.05, 0.05]
    world = spec.worldbody
    _room(spec, scene)
    for t in scene.tables:
        _table(spec, t, _TARGET if t.name == scene.target else _WOOD)
    centre = scene.target_table.box
    for c in scene.chairs:
        _chair(world, c, (centre.x, centre.y), chair_mass_kg, chair_friction)
    mats = _placemats(world, scene)
    heights = {s.item.name: s.item.height for s in starts}
    for s in starts:
        z = s.z + _pile_lift_m(scene, s.item, heights)
        add_body(spec, world, s.item, (s.x, s.y, z), s.yaw, (*kind_rgb(s.item.kind), 1.0))
        spec.add_equality(type=mujoco.mjtEq.mjEQ_WELD, name=f"grip:{s.item.name}",
                          name1="hand", name2=s.item.name, objtype=mujoco.mjtObj.mjOBJ_BODY,
                          active=False, solref=[0.004, 1.0])
    add_cameras(world, scene, mats.get(0))
    model = spec.compile()
    return _index(model, scene, {s.item.name: s.item for s in starts})


def _pile_lift_m(scene: Scene, item: Tableware, heights: dict[str, float]) -> float:
    """How far, metres, ``item`` starts above its table's top: the heights of the objects
    under it when the scene's sources start it in a pile (0 otherwise)."""
    source = scene.source_for(item.name, item.kind)
    if source is None or source.on is None:
        return 0.0
    return scene.resting_z(item.name, item.kind, heights) - scene.table(source.table).height


def _box_geom(body: mujoco.MjsBody, name: str, size: Sequence[float], pos: Sequence[float],
              yaw: float, rgba: Sequence[float], bits: tuple[int, int] = FURNITURE,
              group: int = GROUP_WORLD) -> mujoco.MjsGeom:
    return body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, size=list(size),
                         pos=list(pos), quat=[math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)],
                         rgba=list(rgba), contype=bits[0], conaffinity=bits[1], group=group)


def _cylinder_geom(body: mujoco.MjsBody, name: str, radius: float, half_height: float,
                   z: float, rgba: Sequence[float]) -> mujoco.MjsGeom:
    """An upright furniture cylinder centred ``z`` metres above the body's origin."""
    return body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                         size=[radius, half_height, 0], pos=[0, 0, z], rgba=list(rgba),
                         contype=FURNITURE[0], conaffinity=FURNITURE[1], group=GROUP_WORLD)


def _room(spec: mujoco.MjSpec, scene: Scene) -> None:
    tex = spec.add_texture(name="floor", type=mujoco.mjtTexture.mjTEXTURE_2D,
                           builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, width=256, height=256,
                           rgb1=[0.78, 0.76, 0.72], rgb2=[0.70, 0.68, 0.64])
    mat = spec.add_material(name="floor", texrepeat=[scene.width * 2, scene.depth * 2])
    mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = tex.name
    w, d = scene.width, scene.depth
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE,
                            size=[w / 2, d / 2, 0.1], pos=[w / 2, d / 2, 0], material="floor",
                            contype=FLOOR[0], conaffinity=FLOOR[1], friction=[1.0, 0.01, 0.001])
    spec.worldbody.add_light(name="sun", pos=[w / 2, d / 2, 4.0], dir=[0.2, 0.3, -1.0],
                             type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
                             diffuse=[0.45, 0.45, 0.45], specular=[0.05, 0.05, 0.05],
                             castshadow=False)
    t, hz = 0.05, WALL_HEIGHT_M / 2
    for k, (pos, size) in enumerate((((w / 2, -t), (w / 2 + 2 * t, t)),
                                     ((w / 2, d + t), (w / 2 + 2 * t, t)),
                                     ((-t, d / 2), (t, d / 2)),
                                     ((w + t, d / 2), (t, d / 2)))):
        _box_geom(spec.worldbody, f"outer wall {k}", (*size, hz), (*pos, hz), 0.0, _WALL)
    for k, b in enumerate(scene.walls):
        _box_geom(spec.worldbody, f"wall {k}", (b.width / 2, b.depth / 2, hz), (b.x, b.y, hz),
                  b.yaw, _WALL)


def _table(spec: mujoco.MjSpec, table: SceneTable, rgba: Sequence[float]) -> None:
    """A table: its top (a box, or a cylinder for a round one) on four legs, or on one
    pedestal for a round one. A round top is drawn as a smooth disk (a mesh of
    :data:`ROUND_TOP_FACETS` facets) over its hidden collision cylinder: MuJoCo draws a
    cylinder with few facets, and drawing every cylinder with more slows each frame."""
    name, box, height = table.name, table.box, table.height
    body = spec.worldbody.add_body(name=f"table:{name}", pos=[box.x, box.y, 0],
                                   quat=[math.cos(box.yaw / 2), 0, 0, math.sin(box.yaw / 2)])
    leg_h = (height - TOP_T_M) / 2
    if table.is_round:
        radius = box.width / 2
        top = _cylinder_geom(body, f"top:{name}", radius, TOP_T_M / 2, height - TOP_T_M / 2,
                             rgba)
        top.group = GROUP_COLLISION
        disk = lathe([(0, 0), (radius, 0), (radius, TOP_T_M), (0, TOP_T_M)], ROUND_TOP_FACETS)
        add_look(spec, body, f"top:{name}",
                 [Visual(mujoco.mjtGeom.mjGEOM_MESH, vertices=disk[0] + (0, 0, height - TOP_T_M),
                         faces=disk[1])], rgba)
        # One pedestal: a column on a foot, both well inside the top, so the base (which
        # stands outside the top's edge) never meets them.
        foot = min(PEDESTAL_FOOT_M, 0.8 * radius)
        _cylinder_geom(body, f"leg:{name}:0", min(LEG_M, foot), leg_h, leg_h, _WOOD)
        _cylinder_geom(body, f"leg:{name}:1", foot, FOOT_T_M / 2, FOOT_T_M / 2, _WOOD)
        return
    _box_geom(body, f"top:{name}", (box.width / 2, box.depth / 2, TOP_T_M / 2),
              (0, 0, height - TOP_T_M / 2), 0.0, rgba)
    for k, (sx, sy) in enumerate(((-1, -1), (1, -1), (1, 1), (-1, 1))):
        _box_geom(body, f"leg:{name}:{k}", (LEG_M / 2, LEG_M / 2, leg_h),
                  (sx * (box.width / 2 - LEG_M), sy * (box.depth / 2 - LEG_M), leg_h), 0.0,
                  _WOOD)


def _chair(world: mujoco.MjsBody, chair: Chair, table_xy: tuple[float, float],
           mass_kg: float, friction: float) -> None:
    """A free-standing chair of ``mass_kg`` whose back is on its side away from the target
    table's centre; its legs slide on the floor with ``friction``."""
    b = chair.box
    u, v = b.to_local(*table_xy)
    # The back's direction in the chair's frame: the axis pointing away from the table.
    if abs(u) / b.width > abs(v) / b.depth:
        back = (-math.copysign(1, u), 0.0)
    else:
        back = (0.0, -math.copysign(1, v))
    body = world.add_body(name=f"chair:{chair.name}", pos=[b.x, b.y, 0],
                          quat=[math.cos(b.yaw / 2), 0, 0, math.sin(b.yaw / 2)])
    body.add_freejoint(name=f"chair:{chair.name}")
    seat_share, back_share, leg_share = CHAIR_MASS_SHARES
    hw, hd = b.width / 2, b.depth / 2
    seat = _box_geom(body, f"seat:{chair.name}", (hw, hd, SEAT_T_M / 2), (0, 0, SEAT_Z_M), 0.0,
                     _CHAIR, CHAIR)
    seat.mass = seat_share * mass_kg
    for k, (sx, sy) in enumerate(((-1, -1), (1, -1), (1, 1), (-1, 1))):
        leg = _box_geom(body, f"chair leg:{chair.name}:{k}", (0.02, 0.02, SEAT_Z_M / 2),
                        (sx * (hw - 0.03), sy * (hd - 0.03), SEAT_Z_M / 2), 0.0, _CHAIR, CHAIR)
        leg.mass = leg_share * mass_kg
        # The legs' friction, not the floor's, decides how a chair slides.
        leg.priority = 1
        leg.friction = [friction, 0.005, 0.0001]
    back_h = (BACK_TOP_M - SEAT_Z_M) / 2
    if back[0]:
        size, pos = (0.02, hd, back_h), (back[0] * (hw - 0.02), 0, SEAT_Z_M + back_h)
    else:
        size, pos = (hw, 0.02, back_h), (0, back[1] * (hd - 0.02), SEAT_Z_M + back_h)
    back_geom = _box_geom(body, f"back:{chair.name}", size, pos, 0.0, _CHAIR, CHAIR)
    back_geom.mass = back_share * mass_kg


def _placemats(world: mujoco.MjsBody, scene: Scene) -> dict[int, tuple[float, float]]:
    """A placemat on the target table in front of each diner's seat (table.diners, else the
    contract's one diner), drawn only; where each lies (room frame, metres) by seat index.
    A mat starts at the edge its diner faces and moves in until it lies on the top; all
    mats shrink alike, down to half size, until none overlaps another (diners crowded
    round a small table), and a seat whose mat still cannot lie there goes without."""
    t = scene.target_table
    top = Polygon(t.footprint.outline()).buffer(-PLACEMAT_GAP_M)
    seats = []
    for k, seat in enumerate(scene.target_top.seats):
        here = scene.table_to_room(seat.x, seat.y, seat.yaw)
        ray = LineString([(here.x, here.y), (here.x + 3 * math.cos(here.theta),
                                             here.y + 3 * math.sin(here.theta))])
        if not ray.intersection(top).is_empty:
            seats.append((k, here, Point(here.x, here.y).distance(ray.intersection(top))))
    mats: dict[int, tuple[tuple[float, float], Polygon]] = {}
    for scale in np.linspace(1.0, 0.5, 11):
        width, depth = PLACEMAT_M[0] * scale, PLACEMAT_M[1] * scale
        mats = {}
        for k, here, edge in seats:
            shape = rotate(rectangle(-depth / 2, -width / 2, depth / 2, width / 2),
                           here.theta, origin=(0, 0), use_radians=True)
            for step in range(60):
                d = edge + depth / 2 + 0.005 * step
                centre = (here.x + d * math.cos(here.theta), here.y + d * math.sin(here.theta))
                placed = translate(shape, *centre)
                if top.contains(placed):
                    if not any(placed.intersects(other) for _, other in mats.values()):
                        mats[k] = (centre, placed)
                    break
        if len(mats) == len(seats):
            break
    z = t.height + PLACEMAT_M[2] / 2
    for k, here, _ in seats:
        if k in mats:
            _box_geom(world, f"placemat:{k}", (depth / 2, width / 2, PLACEMAT_M[2] / 2),
                      (*mats[k][0], z), here.theta, _PLACEMAT, (0, 0), GROUP_VISUAL)
    return {k: centre for k, (centre, _) in mats.items()}


def _index(model: mujoco.MjModel, scene: Scene, objects: dict[str, Tableware]) -> WorldModel:
    ng = model.ngeom
    robot_bodies = _subtree(model, model.body("base").id)
    arm_bodies = _subtree(model, model.body("shoulder").id)
    furniture = np.zeros(ng, bool)
    robot = np.zeros(ng, bool)
    arm = np.zeros(ng, bool)
    fingers = np.zeros(ng, bool)
    owner = [""] * ng
    body_owner = {model.body(n).id: n for n in objects}
    for g in range(ng):
        name = model.geom(g).name
        body = int(model.geom_bodyid[g])
        robot[g] = body in robot_bodies
        arm[g] = body in arm_bodies
        fingers[g] = name.startswith(("finger_", "pad_"))
        owner[g] = body_owner.get(body, "")
        furniture[g] = not robot[g] and not owner[g] and name != "floor"
    tops = {t.name: model.geom(f"top:{t.name}").id for t in scene.tables}
    if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"{TRAY}/tray_top") >= 0:
        tops[TRAY_TOP] = model.geom(f"{TRAY}/tray_top").id
    welds = {n: model.equality(f"grip:{n}").id for n in objects}
    parts = {n: np.array([o == n for o in owner]) for n in objects}
    chairs = {c.name: model.body(f"chair:{c.name}").id for c in scene.chairs}
    return WorldModel(model, objects, furniture, robot, arm, fingers, tuple(owner), parts,
                      tops, welds, chairs)


def _subtree(model: mujoco.MjModel, root: int) -> set[int]:
    """Ids of ``root`` and every body below it."""
    out = set()
    for b in range(model.nbody):
        k = b
        while k not in (0, root):
            k = int(model.body_parentid[k])
        if k == root:
            out.add(b)
    return out
