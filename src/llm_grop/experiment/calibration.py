"""Calibrating the planner's feasibility model against a simulator that has sessions.

Two measurements, each a list of ``(x, ok)`` samples in a small room with one 0.9 x 0.6 m
table (metres):

* manipulation: the robot drives to a goal beside the table (with the simulator's own
  arrival error), then picks an object lying at planned reach ``x`` from that goal and puts
  it back; every pick and place attempt is a sample;
* navigation: the robot drives to a goal whose footprint is ``x`` from the table's edge.

:func:`fit` turns the samples into a :class:`ParametricFeasibility` by maximum likelihood
(scipy). ``benchmarks/calibrate_mujoco.py`` runs both for MuJoCo and writes the ``mujoco``
profile.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from llm_grop import seeds
from llm_grop.execution import ExecutionPolicy
from llm_grop.execution.judge import judged_place
from llm_grop.planning.feasibility import ParametricFeasibility
from llm_grop.planning.navigation import Navigator
from llm_grop.simulation.base import Simulator
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Box, Pose2D
from llm_grop.world.request import items_from_names
from llm_grop.world.robot import Robot
from llm_grop.world.scene import Chair, ObjectSource, Scene, SceneTable

#: Objects picked in turn (the paper's Task 8).
OBJECTS = ("dinner plate", "dinner fork", "dinner knife", "mug", "mug lid")
#: The table's near edge is at y = 1.7 in the calibration room.
EDGE_Y = 1.7


@dataclass(frozen=True)
class Sample:
    """One attempt: ``x`` (reach or clearance, metres) and whether it succeeded."""

    x: float
    ok: bool


def room(sources: tuple[ObjectSource, ...] = (), start: Pose2D | None = None) -> Scene:
    """A 6 x 4 m room with the 0.9 x 0.6 m dining table at (3, 2) and nothing else."""
    return Scene(name="calibration room", width=6.0, depth=4.0,
                 tables=(SceneTable("dining table", Box(3.0, 2.0, 0.9, 0.6)),),
                 target="dining table", robot_start=start or Pose2D(3.0, 0.5, math.pi / 2),
                 source_tables=("dining table",), sources=sources, chairs_listed=True)


def measure_manipulation(simulator: Simulator, reaches: Sequence[float], trials: int,
                         seed: int = 0, on_sample: Callable[[Sample], None] | None = None
                         ) -> list[Sample]:
    """Picks and places at each planned reach (metres), ``trials`` episodes each; the goal
    stands 5 to 40 cm from the table's edge."""
    catalog = Catalog.load()
    rng = seeds.stream(seed, "calibration", 0)
    robot = Robot()
    out: list[Sample] = []
    for i, reach in enumerate(reaches):
        for k in range(trials):
            name = OBJECTS[(i + k) % len(OBJECTS)]
            spot = _spot(rng, reach, robot.base_radius_m)
            if spot is None:
                continue
            gx, goal_y, ox, oy = spot
            items = items_from_names([name], catalog)
            scene = room((ObjectSource(name, "dining table", ox, oy),),
                         Pose2D(gx, 0.45, math.pi / 2))
            session = simulator.session(
                scene, items, seeds.stream(seed, "calibration", 1 + i, k),
                replan=Navigator(scene, robot.base_radius_m))
            if not session.navigate(Pose2D(gx, goal_y, math.pi / 2)).ok:
                continue
            picked = session.pick(name)
            out.append(Sample(reach, picked.ok))
            if on_sample:
                on_sample(out[-1])
            if picked.ok:
                u, v, yaw = scene.room_to_table(ox, oy)
                # A place succeeds when the object comes to rest in place, as the
                # executive judges it.
                placed, _ = judged_place(session, scene, name, u, v, yaw, None,
                                         ExecutionPolicy())
                out.append(Sample(reach, placed.ok))
                if on_sample:
                    on_sample(out[-1])
    return out


def _spot(rng: np.random.Generator, reach: float, radius: float
          ) -> tuple[float, float, float, float] | None:
    """A goal ``(x, y)`` south of the table and an object position on the table at
    ``reach`` from it."""
    for _ in range(100):
        gx = float(rng.uniform(2.8, 3.2))
        gy = EDGE_Y - radius - float(rng.uniform(0.05, 0.40))
        angle = float(rng.uniform(math.pi / 2 - 0.7, math.pi / 2 + 0.7))
        ox, oy = gx + reach * math.cos(angle), gy + reach * math.sin(angle)
        if abs(ox - 3.0) <= 0.33 and EDGE_Y + 0.08 <= oy <= 2.25:
            return gx, round(gy, 4), round(ox, 4), round(oy, 4)
    return None


def measure_navigation(simulator: Simulator, clearances: Sequence[float], trials: int,
                       seed: int = 0, on_sample: Callable[[Sample], None] | None = None
                       ) -> list[Sample]:
    """Drives to goals ``clearance`` metres from an obstacle, ``trials`` each: in turn the
    table's long side and a chair's front (the planner's clearance counts both)."""
    catalog = Catalog.load()
    robot = Robot()
    rng = seeds.stream(seed, "calibration", 1000)
    chair = Chair("chair", Box(1.2, 2.6, 0.45, 0.45))
    out: list[Sample] = []
    for i, c in enumerate(clearances):
        for k in range(trials):
            if k % 2 == 0:
                gx, edge, chairs = float(rng.uniform(2.7, 3.3)), EDGE_Y, ()
            else:
                gx, edge, chairs = float(rng.uniform(1.1, 1.3)), 2.6 - 0.225, (chair,)
            goal = Pose2D(gx, edge - robot.base_radius_m - c, math.pi / 2)
            start = Pose2D(float(rng.uniform(1.0, 5.0)), 0.45, math.pi / 2)
            items = items_from_names(["dinner fork"], catalog)
            scene = room((ObjectSource("dinner fork", "dining table", 3.0, 2.1),), start
                         ).with_chairs(chairs)
            session = simulator.session(
                scene, items, seeds.stream(seed, "calibration", 2000 + i, k),
                replan=Navigator(scene, robot.base_radius_m))
            out.append(Sample(c, session.navigate(goal).ok))
            if on_sample:
                on_sample(out[-1])
    return out


def fit(manipulation: Sequence[Sample], navigation: Sequence[Sample],
        robot: Robot | None = None, places: Sequence[Sample] = ()) -> ParametricFeasibility:
    """The parametric model that makes the samples most likely. With ``places``,
    ``manipulation`` holds the picks alone, and places get their own ``place_max`` on the
    same reach curve."""
    robot = robot or Robot()
    nav = _fit([(navigation, lambda p, x: ParametricFeasibility(
        nav_max=p[0], nav_mid_m=p[1], nav_scale_m=p[2]).navigation(x))],
        x0=(0.95, 0.02, 0.03), bounds=((0.05, 1.0), (-0.3, 0.5), (0.003, 0.3)))
    curve = ((0.05, 1.0), (0.3, 0.98), (0.5, 1.6))
    if not places:
        manip = _fit([(manipulation, lambda p, x: ParametricFeasibility(
            manip_max=p[0], knee=p[1], reach_max_m=p[2]).manipulation(x, robot))],
            x0=(0.95, 0.7, 1.0), bounds=curve)
        return ParametricFeasibility(nav[0], nav[1], nav[2], manip[0], manip[1], manip[2])

    def model(p: Sequence[float]) -> ParametricFeasibility:
        return ParametricFeasibility(manip_max=p[0], knee=p[1], reach_max_m=p[2],
                                     place_max=p[3])

    manip = _fit([(manipulation, lambda p, x: model(p).manipulation(x, robot)),
                  (places, lambda p, x: model(p).placing(x, robot))],
                 x0=(0.95, 0.7, 1.0, 0.95), bounds=(*curve, (0.05, 1.0)))
    return ParametricFeasibility(nav[0], nav[1], nav[2], manip[0], manip[1], manip[2],
                                 place_max=manip[3])


def _fit(parts: Sequence[tuple[Sequence[Sample],
                               Callable[[Sequence[float], np.ndarray], np.ndarray]]],
         x0: tuple[float, ...], bounds: tuple[tuple[float, float], ...]) -> list[float]:
    """The parameters that make every part's samples most likely under its model."""
    data = [(np.array([s.x for s in samples], float), np.array([s.ok for s in samples], float),
             model) for samples, model in parts]

    def nll(p: np.ndarray) -> float:
        total = 0.0
        for x, y, model in data:
            q = likelihood_p(model(p, x))
            total -= float(np.sum(y * np.log(q) + (1 - y) * np.log(1 - q)))
        return total

    best = None
    for start in (x0, tuple((lo + hi) / 2 for lo, hi in bounds)):
        r = minimize(nll, np.array(start), method="L-BFGS-B", bounds=bounds)
        if best is None or r.fun < best.fun:
            best = r
    assert best is not None
    return [round(float(v), 4) for v in best.x]


#: The floor and ceiling a fitted success probability is squeezed into, so that one
#: outcome the curve calls certain does not make the likelihood infinite.
P_FLOOR = 1e-4


def likelihood_p(p: np.ndarray) -> np.ndarray:
    """Probabilities ``p`` squeezed linearly into ``[P_FLOOR, 1 - P_FLOOR]``. A clip would
    leave the likelihood flat where the curve saturates, and the optimiser stranded
    there (a navigation top of 1.0 with failures on record)."""
    return P_FLOOR + (1.0 - 2.0 * P_FLOOR) * np.asarray(p, dtype=float)


def rates(samples: Sequence[Sample]) -> dict[float, tuple[int, int]]:
    """Successes and attempts at each ``x``."""
    out: dict[float, tuple[int, int]] = {}
    for s in samples:
        ok, n = out.get(s.x, (0, 0))
        out[s.x] = (ok + s.ok, n + 1)
    return dict(sorted(out.items()))
