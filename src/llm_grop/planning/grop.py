"""GROP: the task-motion plan of maximal utility over M configurations (paper §III-C).

For each configuration, each object gets the standing position that maximises
``w * feasibility - cost`` given the object that follows it, the order is the one of
least total cost with supports first, and the configuration whose plan scores highest
is the one executed. A plan's score is its utility minus a fidelity penalty:
``fidelity_w_s_per_cm`` seconds per centimetre by which the configuration strays from
the stated geometry (:attr:`~llm_grop.world.fidelity.Fidelity.infidelity_m`: its gap
errors plus its origin's shift). Every configuration the sampler gives already keeps the
stated gaps within tolerance, so GROP trades feasibility against cost among faithful
configurations, and the weight says how much a centimetre nearer to what was said is
worth in seconds (0: fidelity plays no part, as in the paper). Navigation legs of the
chosen plan are then planned with OMPL around the sensed chairs. The baselines' *uniform*
standing policy (TPRA, LATP) shares all of this except the standing choice.
"""

from __future__ import annotations

import logging
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from llm_grop import seeds
from llm_grop.errors import Infeasible
from llm_grop.geometry.motion import leg_duration_s
from llm_grop.planning.feasibility import action_times, expected_failures, placing
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.reach import LAST_RESORT_P, repair
from llm_grop.planning.sequencing import best_order, refine, supports_before
from llm_grop.planning.trips import handling_s, plan_trips
from llm_grop.planning.utility import PlanningContext
from llm_grop.world.arrangement import Configuration, Placement
from llm_grop.world.fidelity import Considered, Fidelity
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import Plan, Step

log = logging.getLogger(__name__)

StandingPolicy = Literal["utility", "uniform"]

#: The uniform policy draws among positions whose place succeeds at least this fraction
#: as often as from the best position.
UNIFORM_REACH = 0.5
#: Up to this many objects the order is found exactly for every configuration; beyond
#: it, by local search, with a stated bound on its gap to the optimum
#: (:func:`~llm_grop.planning.sequencing.best_order`).
EXACT_LIMIT = 12
#: Beyond :data:`EXACT_LIMIT` objects, the orders of this many configurations of best
#: score are refined (:func:`~llm_grop.planning.sequencing.refine`) before one is chosen.
REFINE = 3


@dataclass(frozen=True)
class Candidate:
    """One configuration's best plan before paths: order, standing index per object (item
    order), alternatives, expected utility (seconds), feasibility and cost (seconds)."""

    index: int
    placements: tuple[Placement, ...]
    order: tuple[int, ...]
    stand: tuple[int, ...]
    alternatives: tuple[tuple[int, ...], ...]
    utility: float
    feasibility: float
    cost_s: float
    place_p: tuple[float, ...]
    order_optimal: bool = True
    order_gap_s: float = 0.0
    fidelity: Fidelity = Fidelity()
    score: float = 0.0
    considered: tuple[Considered, ...] = ()


def _in_item_order(ctx: PlanningContext, config: Configuration) -> tuple[Placement, ...]:
    by_name = config.by_name()
    return tuple(by_name[i.name] for i in ctx.items)


def evaluate(ctx: PlanningContext, config: Configuration, index: int,
             policy: StandingPolicy = "utility", rng: np.random.Generator | None = None,
             node_budget: int = 0, refined: bool = False) -> Candidate | str:
    """The best plan for ``config``, or the reason none exists.

    ``policy="uniform"`` draws each standing position uniformly (with ``rng``) from those
    within good reach (:data:`UNIFORM_REACH`) instead of maximising utility; the order is
    still the cheapest.
    Beyond :data:`EXACT_LIMIT` objects the order is local search's, followed by a
    branch-and-bound search of up to ``node_budget`` nodes and, when ``refined``, by exact
    re-ordering of windows of it; ``order_gap_s`` states how many
    seconds of utility it may be from the best order's (0 when proven optimal).
    """
    placements = _in_item_order(ctx, config)
    feas = ctx.place_feasibility(placements)
    reason = ctx.unreachable_reason(placements, feas)
    if reason is not None:
        return reason
    v, w = ctx.speed, ctx.options.w
    field = np.array([p.field for p in ctx.pickups])
    dist_in = ctx.dist_m[:, field].T
    if policy == "uniform":
        if rng is None:
            raise ValueError("the uniform standing policy needs a random generator")
        manip = ctx.place_manipulation(placements)
        fixed = []
        for j in range(len(placements)):
            # Like the authors' baselines, which stand at a random side from which the arm
            # reaches: a position counts when its place is at least half as likely to
            # succeed as from the best one. Chairs and path costs are not considered.
            ok = np.flatnonzero((feas[j] > 0) & (manip[j] >= UNIFORM_REACH * manip[j].max()))
            fixed.append(int(rng.choice(ok)))
        score = np.full_like(feas, -np.inf)
        for j, s in enumerate(fixed):
            score[j, s] = w * feas[j, s] - dist_in[j, s] / v
    else:
        score = np.where(feas > 0, w * feas - dist_in / v, -np.inf)
    # out[j, k, s]: value of standing at s for j when the next pickup is field k.
    out = score[:, None, :] - ctx.dist_m.T[None, :, :] / v
    best_next = out.max(axis=2)
    edge = -best_next[:, field]
    np.fill_diagonal(edge, np.inf)
    end = -score.max(axis=1)
    first = ctx.start_dist_m[field] / v
    names = [p.name for p in placements]
    before = supports_before(names, {p.name: p.on for p in placements})
    ordering = best_order(first, edge, end, before, names=names, exact_limit=EXACT_LIMIT,
                          node_budget=node_budget)
    if refined and len(names) > EXACT_LIMIT:
        ordering = refine(first, edge, end, ordering, before)
    if not np.isfinite(ordering.cost):
        return "no order of the objects has a collision-free plan"
    order = ordering.order
    stand, alts = [0] * len(order), [()] * len(order)
    for pos, j in enumerate(order):
        row = out[j, field[order[pos + 1]]] if pos + 1 < len(order) else score[j]
        ranked_all = np.argsort(-row, kind="stable")
        ranked = ranked_all[np.isfinite(row[ranked_all])]
        stand[j] = int(ranked[0])
        alts[j] = tuple(_spread(ctx, ranked[1:], ranked[0], ctx.options.alternatives))
    place_p = [float(feas[j, stand[j]]) for j in range(len(order))]
    utility = -ordering.cost - ctx.fixed_costs_s()
    feasibility = float(np.prod(place_p))
    cost_s = w * sum(place_p) - utility
    return Candidate(index, placements, order, tuple(stand), tuple(alts), float(utility),
                     feasibility, float(cost_s), tuple(place_p), ordering.optimal,
                     ordering.gap)


def _spread(ctx: PlanningContext, ranked: Sequence[int], chosen: int, k: int,
            min_gap_m: float = 0.3) -> list[int]:
    """Up to ``k`` fallbacks from ``ranked``, each ``min_gap_m`` from the others and the
    chosen one, so a chair that blocks one does not block them all."""
    order = np.asarray(ranked, dtype=np.int64)
    ok = ctx.cand_gap_m[chosen, order] >= min_gap_m
    picked: list[int] = []
    while len(picked) < k and ok.any():
        first = int(np.argmax(ok))
        s = int(order[first])
        picked.append(s)
        ok &= ctx.cand_gap_m[s, order] >= min_gap_m
    return picked


def choose(ctx: PlanningContext, configs: Sequence[Configuration],
           policy: StandingPolicy = "utility", rng: np.random.Generator | None = None,
           best_of_all: bool = True, fidelity: Sequence[Fidelity] = ()) -> Candidate:
    """The configuration whose plan scores highest (``best_of_all``), or the first one that
    has a plan; raises :class:`Infeasible` with the reason when none has.

    ``fidelity`` holds one measure per configuration (none: every one counts as faithful);
    the score is the utility minus ``ctx.options.fidelity_w_s_per_cm`` seconds per
    centimetre of infidelity. The returned candidate lists every configuration evaluated.
    """
    if fidelity and len(fidelity) != len(configs):
        raise ValueError(f"{len(fidelity)} fidelity measures for {len(configs)} configurations")
    per_m = 100.0 * ctx.options.fidelity_w_s_per_cm
    fid = list(fidelity) or [Fidelity()] * len(configs)
    reasons: list[str] = []
    found: list[Candidate] = []
    considered: list[Considered] = []
    configs = list(configs)
    cache: dict[int, np.ndarray] = {}
    pool = tuple(configs)
    for i, config in enumerate(pool):
        cand = evaluate(ctx, config, i, policy, rng)
        if policy == "utility":
            cand = _repaired(ctx, cand, i, configs, fid, pool, cache, bool(fidelity))
        if isinstance(cand, str):
            log.debug("configuration %d: no plan: %s", i + 1, cand)
            reasons.append(cand)
            considered.append(Considered(i, None, None, None, fid[i], None))
            continue
        cand = replace(cand, fidelity=fid[i],
                       score=cand.utility - per_m * fid[i].infidelity_m)
        log.debug("configuration %d: utility %.1f s, feasibility %.2f, infidelity %.1f cm",
                  i + 1, cand.utility, cand.feasibility, 100 * fid[i].infidelity_m)
        found.append(cand)
        considered.append(Considered(i, cand.utility, cand.feasibility, cand.cost_s, fid[i],
                                     cand.score))
        if not best_of_all:
            break
    if not found and policy == "utility" and fidelity:
        # Nothing has a plan as sampled: a stated setting may move farther, any way.
        for i in range(len(pool)):
            cand = reasons[i]
            for p_min in LAST_RESORT_P:
                cand = _repaired(ctx, cand, i, configs, fid, pool, cache, True, p_min,
                                 pool[i], fidelity[i])
                if isinstance(cand, str):
                    break  # what no move reaches at all, none reaches more often
            if not isinstance(cand, str):
                cand = replace(cand, fidelity=fid[i],
                               score=cand.utility - per_m * fid[i].infidelity_m)
                found.append(cand)
                considered[i] = Considered(i, cand.utility, cand.feasibility, cand.cost_s,
                                           fid[i], cand.score)
                if not best_of_all:
                    break
    if not found:
        # The commonest reason, the first given among equals: a set's order would change
        # from process to process with Python's string hashing.
        raise Infeasible(f"no plan for any of {len(configs)} configuration(s): "
                         f"{Counter(reasons).most_common(1)[0][0]}")
    if len(ctx.items) > EXACT_LIMIT and policy == "utility":
        top = sorted(found, key=lambda c: (-c.score, c.index))[:REFINE]
        refined = [evaluate(ctx, configs[c.index], c.index, policy, refined=True) for c in top]
        better = [replace(c, fidelity=fid[c.index],
                          score=c.utility - per_m * fid[c.index].infidelity_m)
                  for c in refined if not isinstance(c, str)]
        for c in better:
            considered[c.index] = Considered(c.index, c.utility, c.feasibility, c.cost_s,
                                             c.fidelity, c.score)
        found = better + found
    best = max(found, key=lambda c: (c.score, c.utility, -c.index))
    return replace(best, considered=tuple(considered))


def _repaired(ctx: PlanningContext, cand: Candidate | str, i: int,
              configs: list[Configuration], fid: list[Fidelity],
              pool: Sequence[Configuration], cache: dict[int, np.ndarray], stated: bool,
              last_resort: float = 0.0, base: Configuration | None = None,
              base_fidelity: Fidelity | None = None) -> Candidate | str:
    """``cand`` (the plan of ``configs[i]``, or why it has none), or the plan of ``base``
    (default: ``configs[i]``) repaired for reach (:func:`~llm_grop.planning.reach.repair`;
    ``last_resort`` passed on) when that scores better or only it has a plan;
    ``configs[i]`` and ``fid[i]`` then become the repaired configuration and its
    fidelity."""
    per_m = 100.0 * ctx.options.fidelity_w_s_per_cm
    start = configs[i] if base is None else base
    start_fid = fid[i] if base_fidelity is None else base_fidelity
    fixed = repair(ctx, start, start_fid if stated else None, pool, cache, last_resort)
    if fixed is None:
        return cand
    other = evaluate(ctx, fixed.configuration, i)
    if isinstance(other, str):
        return cand
    if not isinstance(cand, str) and other.utility - per_m * fixed.fidelity.infidelity_m \
            <= cand.utility - per_m * fid[i].infidelity_m:
        return cand
    log.debug("configuration %d: repaired for reach (moved %s m, taken from %s)", i + 1,
              fixed.shifted_m, fixed.taken_from)
    configs[i], fid[i] = fixed.configuration, fixed.fidelity
    return other


def build_plan(ctx: PlanningContext, cand: Candidate, navigator: Navigator, seed: int,
               configurations: int) -> Plan:
    """The chosen candidate as steps, with an OMPL path for every navigation leg.

    With ``capacity > 1`` the objects are grouped into trips that fit the tray
    (:mod:`llm_grop.planning.trips`): all of a trip's pickups, then its placements; the
    standing positions are those of capacity 1, the order is searched anew. Each object
    on a trip of several also costs its load onto the tray and its unload
    (:func:`~llm_grop.planning.trips.handling_s`), which the plan's expected duration
    counts. Both the trips and one object per trip get paths, and the plan of shorter
    expected duration is kept, so more capacity is never slower in the plan.
    """
    robot = ctx.scene.robot
    before = supports_before([p.name for p in cand.placements],
                             {p.name: p.on for p in cand.placements})
    failed_s = action_times(ctx.model, robot).failed_attempt_s
    trips, _ = plan_trips(ctx, cand.order, cand.stand, robot.capacity, before)
    steps = _steps(ctx, cand, trips, navigator, seed)
    on_tray = sum(len(t) for t in trips if len(t) > 1)
    extra_s = on_tray * handling_s(ctx) if on_tray else 0.0
    # The candidate's cost assumed one object per trip; credit what the trips save.
    saved_s = 0.0
    if len(trips) < len(cand.order):
        singles = _steps(ctx, cand, tuple((j,) for j in cand.order), navigator, seed)
        saved_s = expected_duration_s(singles, failed_s) \
            - expected_duration_s(steps, failed_s) - extra_s
        if saved_s <= 0:
            steps, saved_s, trips = singles, 0.0, tuple((j,) for j in cand.order)
            extra_s = 0.0
    names = tuple(cand.placements[j].name for trip in trips for j in trip)
    return Plan(order=names, steps=steps, configuration=cand.placements,
                expected_duration_s=expected_duration_s(steps, failed_s) + extra_s,
                configuration_index=cand.index, utility=cand.utility + saved_s,
                feasibility=cand.feasibility, cost_s=cand.cost_s - saved_s,
                configurations_considered=configurations, fidelity=cand.fidelity,
                considered=cand.considered,
                fidelity_w_s_per_cm=ctx.options.fidelity_w_s_per_cm)


def _duration(steps: Sequence[Step]) -> float:
    """Expected seconds of ``steps`` when nothing fails."""
    return sum(s.duration_s for s in steps)


def expected_duration_s(steps: Sequence[Step], failed_attempt_s: float) -> float:
    """Expected seconds of ``steps`` with retries: each step's duration, plus
    ``failed_attempt_s`` for each of its expected failed attempts (``1/p - 1`` for success
    probability ``p``, counted down to :data:`~llm_grop.planning.feasibility.MIN_RETRY_P`)."""
    retries = sum(expected_failures(s.success_p) for s in steps)
    return _duration(steps) + failed_attempt_s * retries


def _steps(ctx: PlanningContext, cand: Candidate, trips: Sequence[tuple[int, ...]],
           navigator: Navigator, seed: int) -> tuple[Step, ...]:
    """The steps of ``cand`` carried out as ``trips``, with OMPL paths."""
    scene, robot = ctx.scene, ctx.scene.robot
    times = action_times(ctx.model, robot)
    steps: list[Step] = []
    here = scene.robot_start
    leg = 0

    def go(goal: Pose2D, obj: str, alternatives: tuple[Pose2D, ...], p: float) -> Pose2D:
        nonlocal here, leg
        for g in (goal, *alternatives):
            path = navigator.plan((here.x, here.y), (g.x, g.y),
                                  seed=seeds.int_seed(seed, "ompl", leg))
            if path is not None:
                leg += 1
                steps.append(Step("navigate", obj, goal=g, path=path, success_p=p,
                                  duration_s=leg_duration_s(here, g, path, robot)
                                  + times.leg_overhead_s,
                                  alternatives=tuple(a for a in alternatives if a != g)))
                here = g
                return g
        raise Infeasible(f"no collision-free path to {'pick up' if p else 'place'} {obj!r} "
                         f"from ({here.x:.2f}, {here.y:.2f})")

    for trip in trips:
        for j in trip:
            pu = ctx.pickups[j]
            p_nav = float(ctx.model.navigation(np.array([pu.standing.clearance_m]))[0])
            go(pu.standing.pose, pu.item, (), p_nav)
            steps.append(Step("pick", pu.item, standing=pu.standing.pose,
                              pose=(pu.source.x, pu.source.y, 0.0),
                              duration_s=times.pick_s,
                              success_p=_manip(ctx, pu.standing.pose, (pu.source.x, pu.source.y))))
        for j in trip:
            p = cand.placements[j]
            s = ctx.candidates[cand.stand[j]]
            alts = tuple(ctx.candidates[a].pose for a in cand.alternatives[j])
            stood = go(s.pose, p.name, alts, float(ctx.cand_nav_p[cand.stand[j]]))
            target = ctx.targets_room([p])[0]
            steps.append(Step("place", p.name, standing=stood, pose=(p.x, p.y, p.yaw),
                              duration_s=times.place_s,
                              success_p=_manip(ctx, stood, (target[0], target[1]), place=True)))
    return tuple(steps)


def _manip(ctx: PlanningContext, stand: Pose2D, xy: tuple[float, float], place: bool = False
           ) -> float:
    """The feasibility model's success probability of a pick (or a ``place``) at ``xy``
    from ``stand``."""
    r = np.array([float(np.hypot(xy[0] - stand.x, xy[1] - stand.y))])
    robot = ctx.scene.robot
    return float((placing(ctx.model, r, robot) if place else ctx.model.manipulation(r, robot))[0])
