"""Navigation: cost-to-go fields on the occupancy grid and OMPL paths (room frame, metres).

GROP evaluates thousands of (standing position, pickup) pairs per episode, so it reads
path lengths from cost-to-go fields: one Dijkstra search per pickup over the grid's free
cells, 16-connected so grid distances stay within about 3 % of Euclidean ones. Only the
chosen plan's legs are planned with a sampling planner (OMPL's RRTConnect in R², then
shortcut), and the simulator replans with it after a failure.

A path depends on its seed and obstacles alone, never on the clock: RRTConnect stops
when it has a path or after :data:`PATH_ITERATIONS` iterations, and its time limit is a
safety net far above what those iterations take, so a slow or busy machine finds the
same paths (and gives up on the same legs) as a fast one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage, sparse
from scipy.sparse import csgraph

from llm_grop.geometry.obstacles import Floats, Obstacles
from llm_grop.planning.occupancy import OccupancyGrid
from llm_grop.world.geometry2d import Disc
from llm_grop.world.scene import Scene

Point = tuple[float, float]

#: A sensed point is avoided as a disc of this radius, metres (a chair leg's half width).
SENSED_RADIUS_M = 0.03
#: Sensed points are thinned to one per square cell of this side, metres.
SENSED_CELL_M = 0.04
#: Paths keep this much more than the base's radius from obstacles where there is room
#: (a costmap's inflation), tapering to none at their two ends, metres; where no such path
#: exists, they keep the radius alone.
PATH_MARGIN_M = 0.06
#: RRTConnect's iterations (evaluations of its termination condition) before it gives up
#: on a path. The paper's tasks need at most about 150 (tasks 1-8, 20 trials each); a
#: path for the 0.6 m base through a 0.74 m doorway that keeps PATH_MARGIN_M up to about
#: 8,000. 20,000 fruitless iterations take about 0.1 s of CPU.
PATH_ITERATIONS = 20_000
#: Seconds after which RRTConnect stops even before :data:`PATH_ITERATIONS`: a safety net
#: against a runaway search only, far above what the iterations take even on a machine
#: a hundred times slower, so that no run's result depends on it.
PATH_TIME_LIMIT_S = 60.0

#: Cell size, metres, of the clearance lookup that answers most of RRTConnect's validity
#: checks without testing every obstacle (:class:`_FreeLookup`).
LOOKUP_CELL_M = 0.1

#: Grid moves (row, column) of the 16-connected neighbourhood, one of each opposite pair.
_MOVES = ((0, 1), (1, 0), (1, 1), (1, -1), (1, 2), (2, 1), (2, -1), (1, -2))


class CostField:
    """Shortest collision-free path length, metres, from one source to anywhere."""

    def __init__(self, graph: NavGraph, dist: Floats) -> None:
        self._graph, self._dist = graph, dist

    def cost_at(self, xy: Floats) -> Floats:
        """Path length, metres, from the source to each room-frame point of ``xy`` (``(N, 2)``);
        ``inf`` where unreachable. A point joins the grid at the free cell centres around it,
        or at the nearest free cell when it is itself blocked."""
        cells, extra = self._graph.neighbours(xy)
        return np.min(self._dist[cells] + extra, axis=1)


class NavGraph:
    """The free cells of a grid for a round base of ``radius_m``, as a weighted graph."""

    def __init__(self, grid: OccupancyGrid, radius_m: float) -> None:
        self.grid = grid
        free = grid.clearance_m >= radius_m
        rows, cols = free.shape
        index = np.arange(rows * cols).reshape(rows, cols)
        heads, tails, weights = [], [], []
        for di, dj in _MOVES:
            a = free[max(0, -di):rows - max(0, di), max(0, -dj):cols - max(0, dj)]
            ok = a & _shifted(free, di, dj)
            # A move may not cut a corner: the cells it sweeps must be free too.
            for si, sj in _swept(di, dj):
                ok &= _shifted(free, si, sj, di, dj)
            src = index[max(0, -di):rows - max(0, di), max(0, -dj):cols - max(0, dj)][ok]
            heads.append(src)
            tails.append(src + di * cols + dj)
            weights.append(np.full(src.size, math.hypot(di, dj) * grid.resolution_m))
        self._edges = (np.concatenate(heads), np.concatenate(tails), np.concatenate(weights))
        self.free = free
        _, nearest = ndimage.distance_transform_edt(~free, return_indices=True)
        self._nearest = nearest[0] * cols + nearest[1]

    def neighbours(self, xy: Floats) -> tuple[NDArray[np.int64], Floats]:
        """For each point, the 4 cells whose centres surround it and the distances to those
        centres, metres, both ``(N, 4)``; blocked cells get the nearest free cell instead."""
        pts = np.asarray(xy, dtype=float).reshape(-1, 2)
        res = self.grid.resolution_m
        rows, cols = self.grid.shape
        i0 = np.floor(pts[:, 1] / res - 0.5).astype(np.int64)
        j0 = np.floor(pts[:, 0] / res - 0.5).astype(np.int64)
        ii = np.clip(np.stack([i0, i0, i0 + 1, i0 + 1], axis=1), 0, rows - 1)
        jj = np.clip(np.stack([j0, j0 + 1, j0, j0 + 1], axis=1), 0, cols - 1)
        flat = self._nearest[ii, jj]
        cy, cx = (flat // cols + 0.5) * res, (flat % cols + 0.5) * res
        return flat, np.hypot(cx - pts[:, :1], cy - pts[:, 1:])

    def fields(self, sources: Sequence[Point]) -> list[CostField]:
        """One cost-to-go field per source point (a single Dijkstra call over the grid plus
        one extra node per source, joined to the cells around it)."""
        if not sources:
            return []
        n = self.free.size
        if not self.free.any():
            return [CostField(self, np.full(n, np.inf)) for _ in sources]
        cells, extra = self.neighbours(np.array(sources, dtype=float))
        k = len(sources)
        heads, tails, weights = self._edges
        hub = np.repeat(n + np.arange(k), cells.shape[1])
        # Zero-length edges would vanish from a sparse matrix.
        matrix = sparse.csr_array(
            (np.concatenate([weights, np.maximum(extra.ravel(), 1e-9)]),
             (np.concatenate([heads, hub]), np.concatenate([tails, cells.ravel()]))),
            shape=(n + k, n + k))
        dist = csgraph.dijkstra(matrix, directed=False, indices=n + np.arange(k))
        return [CostField(self, dist[i, :n]) for i in range(k)]


def _shifted(free: NDArray[np.bool_], si: int, sj: int, di: int | None = None,
             dj: int | None = None) -> NDArray[np.bool_]:
    """``free`` at offset ``(si, sj)`` over the region where move ``(di, dj)`` starts."""
    di = si if di is None else di
    dj = sj if dj is None else dj
    rows, cols = free.shape
    r0, c0 = max(0, -di), max(0, -dj)
    r1, c1 = rows - max(0, di), cols - max(0, dj)
    return free[r0 + si:r1 + si, c0 + sj:c1 + sj]


def _swept(di: int, dj: int) -> tuple[tuple[int, int], ...]:
    """Cells, relative to the start, that a straight move ``(di, dj)`` passes through."""
    if abs(di) + abs(dj) <= 1:
        return ()
    if abs(di) == 1 and abs(dj) == 1:
        return ((di, 0), (0, dj))
    if abs(dj) == 2:
        return ((0, dj // 2), (di, dj // 2))
    return ((di // 2, 0), (di // 2, dj))


class Navigator:
    """Collision-free paths for a round base, with OMPL's RRTConnect in R².

    Attributes:
        obstacles: what the paths avoid (with the sensed chairs when ``include_chairs``).
        radius_m: the base's radius, metres.
        time_limit_s: OMPL's safety-net time limit per path, seconds (see
            :data:`PATH_TIME_LIMIT_S`); a path ends on ``iterations``, not on it.
        iterations: RRTConnect's iterations per path before it gives up.
    """

    def __init__(self, scene: Scene, robot_radius_m: float, *, include_chairs: bool = True,
                 time_limit_s: float = PATH_TIME_LIMIT_S, sensed: tuple[Disc, ...] = (),
                 iterations: int = PATH_ITERATIONS) -> None:
        self.scene = scene
        self.include_chairs = include_chairs
        self.obstacles = Obstacles(scene, include_chairs, sensed)
        self.radius_m = robot_radius_m
        self.time_limit_s = time_limit_s
        self.iterations = iterations
        self._lookup: _FreeLookup | None = None

    def with_sensed(self, points: Sequence[Point]) -> Navigator:
        """This navigator also avoiding ``points`` the robot's sensors saw (room frame),
        each a disc of :data:`SENSED_RADIUS_M`; points on known obstacles are dropped, and
        the rest thinned to one per :data:`SENSED_CELL_M` cell."""
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if not len(pts):
            return self
        pts = pts[self.obstacles.clearance(pts) > SENSED_CELL_M]
        _, first = np.unique(np.floor(pts / SENSED_CELL_M).astype(int), axis=0,
                             return_index=True)
        discs = tuple(Disc(float(x), float(y), SENSED_RADIUS_M) for x, y in pts[np.sort(first)])
        if not discs:
            return self
        return Navigator(self.scene, self.radius_m, include_chairs=self.include_chairs,
                         time_limit_s=self.time_limit_s, sensed=discs,
                         iterations=self.iterations)

    def free_lookup(self) -> _FreeLookup:
        """The exact disc test of :attr:`obstacles`, sped up by a clearance grid (built on
        first use)."""
        if self._lookup is None:
            self._lookup = _FreeLookup(self.obstacles)
        return self._lookup

    def valid(self, xy: Floats) -> NDArray[np.bool_]:
        """Whether the base fits at each room-frame point of ``xy`` (``(N, 2)``)."""
        return self.obstacles.clearance(xy) >= self.radius_m - 1e-9

    def segment_free(self, a: Point, b: Point, step_m: float = 0.02) -> bool:
        """Whether the base can drive straight from ``a`` to ``b``."""
        return self.obstacles.segment_free(a, b, self.radius_m, step_m)

    def plan(self, start: Point, goal: Point, seed: int,
             obstacles: Sequence[Point] = ()) -> tuple[Point, ...] | None:
        """A shortcut path from ``start`` to ``goal``, also around the sensed
        ``obstacles`` (room-frame points), or ``None`` when none was found.

        The same ``seed`` and obstacles give the same path.
        """
        if len(obstacles):
            nav = self.with_sensed(obstacles)
            if nav is not self:
                return nav.plan(start, goal, seed)
        ends = np.array([start, goal], dtype=float)
        if not self.valid(ends).all():
            return None
        for margin in (PATH_MARGIN_M, 0.0):
            if self._clear(start, goal, ends, margin):
                return (tuple(map(float, start)), tuple(map(float, goal)))  # type: ignore[return-value]
            path = _ompl_path(self, start, goal, seed, margin)
            if path is not None:
                return path
        return None

    def required_m(self, xy: Floats, ends: Floats, margin_m: float) -> Floats:
        """The clearance, metres, a path keeps at each room-frame point of ``xy``: the
        radius plus ``margin_m``, tapering to the radius alone at the ``ends``."""
        pts = np.asarray(xy, dtype=float).reshape(-1, 2)
        d_end = np.min(np.hypot(pts[:, None, 0] - ends[None, :, 0],
                                pts[:, None, 1] - ends[None, :, 1]), axis=1)
        return self.radius_m + np.minimum(margin_m, 0.5 * d_end)

    def _clear(self, a: Point, b: Point, ends: Floats, margin_m: float,
               step_m: float = 0.02) -> bool:
        """Whether the straight segment from ``a`` to ``b`` keeps :meth:`required_m`."""
        if margin_m <= 0:
            return self.segment_free(a, b, step_m)
        n = max(2, math.ceil(math.dist(a, b) / step_m) + 1)
        pts = np.linspace(a, b, n)
        return bool((self.obstacles.clearance(pts)
                     >= self.required_m(pts, ends, margin_m) - 1e-9).all())


class _FreeLookup:
    """:meth:`Obstacles.free` with the same answers, faster: clearance is 1-Lipschitz, so
    the exact clearance at the centre of a :data:`LOOKUP_CELL_M` cell decides every point
    of the cell whose answer it settles beyond the cell's half diagonal; only points near
    the threshold are tested against every obstacle."""

    #: Decisions closer than this to the threshold, metres, go to the exact test.
    _GUARD_M = 1e-6

    def __init__(self, obstacles: Obstacles, cell_m: float = LOOKUP_CELL_M) -> None:
        self._exact = obstacles.free
        self.cell_m = cell_m
        self.cols = max(1, math.ceil(obstacles.width / cell_m))
        self.rows = max(1, math.ceil(obstacles.depth / cell_m))
        jj, ii = np.meshgrid(np.arange(self.cols), np.arange(self.rows))
        centres = (np.stack([jj.ravel(), ii.ravel()], axis=1) + 0.5) * cell_m
        #: Exact clearance at each cell's centre, metres, row by row (a list: read one
        #: at a time).
        self.clearance: list[float] = obstacles.clearance(centres).tolist()
        #: The cell's half diagonal plus the guard, metres.
        self.half_m = cell_m * math.sqrt(0.5) + self._GUARD_M

    def free(self, x: float, y: float, radius_m: float) -> bool:
        """Whether a disc of ``radius_m`` at room-frame ``(x, y)`` touches nothing
        (:meth:`Obstacles.free`'s answer)."""
        j, i = int(x / self.cell_m), int(y / self.cell_m)
        if 0 <= i < self.rows and 0 <= j < self.cols and x >= 0 and y >= 0:
            c = self.clearance[i * self.cols + j]
            if c - self.half_m >= radius_m:
                return True
            if c + self.half_m < radius_m:
                return False
        return self._exact(x, y, radius_m)


def _ompl_path(nav: Navigator, start: Point, goal: Point, seed: int, margin_m: float
               ) -> tuple[Point, ...] | None:
    """RRTConnect, then OMPL's shortcutting, keeping :meth:`Navigator.required_m` with
    ``margin_m``; OMPL objects stay local to this call."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    ou.RNG.setSeed(int(seed) % (2**31 - 1) + 1)
    space = ob.RealVectorStateSpace(2)
    bounds = ob.RealVectorBounds(2)
    bounds.setLow(0.0)
    bounds.setHigh(0, nav.scene.width)
    bounds.setHigh(1, nav.scene.depth)
    space.setBounds(bounds)
    si = ob.SpaceInformation(space)
    lookup = nav.free_lookup()
    free, radius = lookup.free, nav.radius_m - 1e-9
    (sx, sy), (gx, gy) = start, goal
    cells, cols, rows, cell, half = (lookup.clearance, lookup.cols, lookup.rows,
                                     lookup.cell_m, lookup.half_m)
    widest = radius + margin_m

    def valid(s: ob.State) -> bool:
        x, y = s[0], s[1]
        # The lookup's decisive cases first: the required clearance lies between the
        # radius and the radius plus the margin, whatever the taper.
        j, i = int(x / cell), int(y / cell)
        if 0 <= i < rows and 0 <= j < cols and x >= 0 and y >= 0:
            c = cells[i * cols + j]
            if c - half >= widest:
                return True
            if c + half < radius:
                return False
        taper = 0.5 * min(math.hypot(x - sx, y - sy), math.hypot(x - gx, y - gy))
        return free(x, y, radius + min(margin_m, taper))

    si.setStateValidityChecker(valid)
    # Motions are checked every 4 cm; the result is then pulled taut with 2 cm checks.
    si.setStateValidityCheckingResolution(0.04 / max(nav.scene.width, nav.scene.depth))
    si.setup()
    pdef = ob.ProblemDefinition(si)
    s, g = space.allocState(), space.allocState()
    s[0], s[1] = float(start[0]), float(start[1])
    g[0], g[1] = float(goal[0]), float(goal[1])
    pdef.setStartAndGoalStates(s, g)
    planner = og.RRTConnect(si)
    planner.setProblemDefinition(pdef)
    planner.setup()
    # The bindings have no iteration condition of their own. RRTConnect evaluates this one
    # once per iteration (and a few times more while it takes the start and goal, the same
    # number each time), and stops by itself on an exact solution.
    done = [0]

    def enough() -> bool:
        done[0] += 1
        return done[0] > nav.iterations

    planner.solve(ob.plannerOrTerminationCondition(
        ob.PlannerTerminationCondition(enough),
        ob.timedPlannerTerminationCondition(nav.time_limit_s)))
    if not pdef.hasExactSolution():
        return None
    path = pdef.getSolutionPath()
    og.PathSimplifier(si).simplifyMax(path)
    pts = [(float(q[0]), float(q[1])) for q in path.getStates()]
    pts[0], pts[-1] = (float(start[0]), float(start[1])), (float(goal[0]), float(goal[1]))
    return _taut(nav, pts, margin_m)


def _taut(nav: Navigator, pts: list[Point], margin_m: float) -> tuple[Point, ...]:
    """``pts`` with every vertex skipped that a straight free segment can bypass."""
    ends = np.array([pts[0], pts[-1]], dtype=float)
    out = [pts[0]]
    i = 0
    while i < len(pts) - 1:
        j = len(pts) - 1
        while j > i + 1 and not nav._clear(pts[i], pts[j], ends, margin_m):
            j -= 1
        out.append(pts[j])
        i = j
    return tuple(out)
