"""Planning time as objects and diners grow, and the trip grouping's optimality gap.

Planning time is what ``planning_time_s`` of a run holds (LLM calls excluded): the
arrangement's M = 25 configurations, the standing positions, the cost-to-go fields, the
utility of every configuration, the order and the OMPL paths. It is measured here by
calling the planning stage (:func:`llm_grop.methods.episode.plan_episode`) on a scene set
up as ``llm_grop.api.run`` sets it up, so cases beyond a request's 30 objects can be timed:

* Task 8 (5 objects), LLM-GROP, the embedded model's recorded answers replayed, 1 chair;
* 10, 20 and 40 objects, GROP (random arrangements), 1.8 x 0.9 m table, banquet room;
* 2, 4, 6 and 8 diners x 4 objects (dinner plate, dinner fork, dinner knife, water cup
  each), LLM-GROP with the packaged preferences (no LLM call), 1.8 x 0.9 m table,
  banquet room (``data/banquet_room.yaml``), 1 chair.

Each line gives the median and p95 (nearest rank) over the seeds, and how many seeds had
no plan. Then the trip grouping (capacity > 1, :mod:`llm_grop.planning.trips`) is
compared with exhaustive search over every order and every cut into trips, on instances
small enough to enumerate.
Run: .venv/bin/python benchmarks/family_planning.py [--seeds 20] [--quick]
"""

from __future__ import annotations

import argparse
import itertools
import statistics
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

from common import median_p95, parse_args, replay_llm

from llm_grop.api import plan
from llm_grop.arrangement.diners import seat_items, seat_table
from llm_grop.arrangement.pipeline import ArrangeOptions
from llm_grop.arrangement.preferences import load_preference_file
from llm_grop.errors import LLMGropError
from llm_grop.files.scene_file import load_scene, set_target_top
from llm_grop.methods.base import EpisodeInput
from llm_grop.methods.episode import plan_episode
from llm_grop.methods.registry import get_method
from llm_grop.planning.feasibility import feasibility_profile
from llm_grop.planning.grop import Candidate, evaluate
from llm_grop.planning.sequencing import supports_before
from llm_grop.planning.trips import cut_order, plan_trips, trip_costs
from llm_grop.planning.utility import PlanningContext
from llm_grop.simulation.scenario import prepare_episode
from llm_grop.world.arrangement import Configuration, Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.table import Table

DATA = Path(__file__).parent / "data"
BANQUET = DATA / "banquet_room.yaml"
TABLE = Table.parse("1.8x0.9")
#: The objects of the 10-, 20- and 40-object cases, in order (the first 10, the first
#: 20, all); a repeated kind is another instance.
OBJECTS = ("dinner plate", "bread plate", "dinner fork", "salad fork", "dinner knife",
           "soup spoon", "water cup", "mug", "mug mat", "napkin",
           "salad plate", "dinner fork", "dinner knife", "butter knife", "teaspoon",
           "teaspoon", "wine glass", "mug lid", "strawberry", "bread")
SETTING = ("dinner plate", "dinner fork", "dinner knife", "water cup")
WORDS = {2: "two", 4: "four", 6: "six", 8: "eight"}
CATALOG = Catalog.load(use_env=False)


def numbered(kinds: Sequence[str], diner: int | None = None, first: int = 1
             ) -> list[Item]:
    """Items of ``kinds``, a repeated kind numbered ("dinner fork 2"), counting from the
    ``first``-th instance of each kind."""
    seen: dict[str, int] = {}
    out = []
    for kind in kinds:
        seen[kind] = seen.get(kind, first - 1) + 1
        name = kind if seen[kind] == 1 else f"{kind} {seen[kind]}"
        out.append(Item(name, CATALOG.resolve(kind, "objects"), diner))
    return out


def objects(n: int) -> tuple[Item, ...]:
    """``n`` objects (one diner), :data:`OBJECTS` repeated as needed."""
    return tuple(numbered([OBJECTS[k % len(OBJECTS)] for k in range(n)]))


def diners(n: int) -> tuple[Item, ...]:
    """``n`` diners' settings of :data:`SETTING`, numbered across the diners as a request
    "for N with ..." numbers them."""
    out: list[Item] = []
    for d in range(n):
        out += numbered(SETTING, d, first=d + 1)
    return tuple(out)


def planning_s(method: str, items: tuple[Item, ...], request: str, seed: int,
               options: ArrangeOptions, capacity: int = 1) -> float:
    """Planning time, seconds, of ``method`` for ``items`` on the 1.8 x 0.9 m table of the
    banquet room with 1 chair, set up as ``llm_grop.api.run`` sets it up."""
    return planned(method, items, request, seed, options, capacity)[0].planning_time_s


def planned(method: str, items: tuple[Item, ...], request: str, seed: int,
            options: ArrangeOptions, capacity: int = 1):  # type: ignore[no-untyped-def]
    """:func:`planning_s`'s planned episode and its items (a robot of ``capacity``)."""
    base = set_target_top(load_scene(BANQUET), TABLE, keep_chairs=False)
    base = replace(base, robot=replace(base.robot, capacity=capacity))
    items = seat_items(items, base.target_top)
    top = seat_table(base.target_top, items)
    if top.diners and not base.diners:
        base = replace(base, diners=top.diners)
    scene = prepare_episode(base, items, seed, chairs=1)
    chosen = get_method(method)
    llm = replay_llm() if chosen.arrangement.uses_llm else None
    inp = EpisodeInput(request, items, top, seed, CATALOG, llm, options)
    return plan_episode(chosen, inp, scene), items


def trip_gap(n: int, capacity: int, seed: int) -> tuple[float, float, float]:
    """Cost, seconds (driving, and each object's load and unload on a trip of several;
    trips fit the tray), of the trips GROP plans for ``n`` objects (the first
    ``n`` of :data:`OBJECTS`, random arrangement) with a robot of ``capacity``; of the
    capacity-1 order's best cut into trips (what GROP planned up to version 0.17); and
    the least over every order of the objects and every cut of it into trips (the same
    standing positions, the same trip model: a trip's pickups, then its places)."""
    episode, items = planned("grop", objects(n), f"{n} objects", seed, ArrangeOptions(),
                             capacity)
    ctx = PlanningContext(episode.scene, items, feasibility_profile(episode.feasibility))
    cand = evaluate(ctx, Configuration(episode.plan.configuration),
                    episode.plan.configuration_index)
    assert isinstance(cand, Candidate)
    costs = trip_costs(ctx, cand.stand, capacity)
    before = supports_before([p.name for p in cand.placements],
                             {p.name: p.on for p in cand.placements})
    trips, _ = plan_trips(ctx, cand.order, cand.stand, capacity, before, costs)
    ours = cut_order(ctx, [j for t in trips for j in t], cand.stand, costs)[1]
    cut = cut_order(ctx, cand.order, cand.stand, costs)[1]
    best = min(ours, cut)
    for perm in itertools.permutations(range(n)):
        pos = {j: k for k, j in enumerate(perm)}
        if any(pos[a] > pos[b] for a, b in before):
            continue
        best = min(best, cut_order(ctx, perm, cand.stand, costs)[1])
    return ours, cut, best


def report(label: str, seeds: int, one: Callable[[int], float]) -> None:
    """One line: median and p95 of ``one(seed)`` in milliseconds over ``seeds`` seeds."""
    times, failed = [], []
    for seed in range(seeds):
        try:
            times.append(1000 * one(seed))
        except LLMGropError as exc:
            failed.append(f"seed {seed}: {exc}")
    if times:
        med, p95 = median_p95(times)
        print(f"{label}: median {med:.0f} ms, p95 {p95:.0f} ms "
              f"({len(times)} of {seeds} seeds planned)", flush=True)
    else:
        print(f"{label}: no seed planned", flush=True)
    for f in failed[:3]:
        print(f"  {f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--objects", default="10,20,40")
    ap.add_argument("--diners", default="2,4,6,8")
    ap.add_argument("--trip-objects", default="4,5,6,7",
                    help="object counts of the trip grouping's optimality gap")
    ap.add_argument("--trip-seeds", type=int, default=10)
    args = parse_args(ap, {"seeds": 1, "objects": "10", "diners": "2",
                           "trip_objects": "4", "trip_seeds": 1})
    llm = replay_llm()
    report("Task 8 (5 objects), LLM-GROP, 0.9 x 0.6 m table", args.seeds,
           lambda seed: plan(task=8, method="llm-grop", seed=seed, chairs=1,
                             llm=llm).planned.planning_time_s)
    plain = ArrangeOptions()
    for n in (int(k) for k in args.objects.split(",") if k):
        report(f"{n} objects, GROP, 1.8 x 0.9 m table", args.seeds,
               lambda seed, n=n: planning_s("grop", objects(n), f"{n} objects", seed, plain))
    prefs = ArrangeOptions(preference_pool=load_preference_file(DATA / "preferences.yaml"))
    for n in (int(k) for k in args.diners.split(",") if k):
        request = f"set the table for {WORDS.get(n, n)} with a {', a '.join(SETTING)}"
        report(f"{n} diners x 4 objects, LLM-GROP (preferences), 1.8 x 0.9 m table",
               args.seeds,
               lambda seed, n=n, r=request: planning_s("llm-grop", diners(n), r, seed, prefs))
    print("Trip grouping (capacity > 1) against every order and every cut into trips "
          "(seconds: driving, loads and unloads; trips fit the tray; same standing positions):")
    for capacity in (2, 3):
        for n in (int(k) for k in args.trip_objects.split(",") if k):
            gaps, cut_gaps, optimal = [], [], 0
            for seed in range(args.trip_seeds):
                ours, cut, best = trip_gap(n, capacity, seed)
                gaps.append(ours / best - 1)
                cut_gaps.append(cut / best - 1)
                optimal += ours <= best + 1e-9
            print(f"  capacity {capacity}, {n} objects: gap mean "
                  f"{100 * statistics.fmean(gaps):.1f}%, max {100 * max(gaps):.1f}%, optimal "
                  f"in {optimal} of {args.trip_seeds} seeds (the capacity-1 order cut into "
                  f"trips: mean {100 * statistics.fmean(cut_gaps):.1f}%, "
                  f"max {100 * max(cut_gaps):.1f}%)", flush=True)


if __name__ == "__main__":
    main()
