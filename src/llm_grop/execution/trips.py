"""A plan's trips, as the executive carries them out.

A plan cuts its order into trips (:mod:`llm_grop.planning.trips`): on each, the robot
drives to and picks each of the trip's objects in turn, then drives to and places each in
the same order. Read back from the plan's steps, each object of a trip has its pickup leg
and pick, and its delivery leg and place. A trip of one object rides in the hand, as with
capacity 1; a trip of several rides on the robot's tray: each object is loaded onto it
after its pick, and unloaded from it before its place.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from llm_grop.world.plan import Step


@dataclass(frozen=True)
class Carry:
    """One object's part of a trip: the navigation leg to its pickup (``None`` when the
    plan has none) and its pick, the leg to where it is placed and its place."""

    object: str
    pickup_leg: Step | None
    pick: Step
    place_leg: Step | None
    place: Step


@dataclass(frozen=True)
class Trip:
    """Objects carried together, in the order they are picked and placed."""

    carries: tuple[Carry, ...]

    @property
    def objects(self) -> tuple[str, ...]:
        """The trip's objects, in order."""
        return tuple(c.object for c in self.carries)


def plan_trips(steps: Sequence[Step]) -> tuple[Trip, ...] | None:
    """The trips of a plan's ``steps``; ``None`` when the steps are not trips (a pick
    after which the same object is never placed, or a place of an object never picked),
    which the executive then runs one step after another."""
    trips: list[list[str]] = []
    legs: dict[tuple[str, str], Step] = {}
    acts: dict[tuple[str, str], Step] = {}
    placing = True
    for k, step in enumerate(steps):
        name = step.object or ""
        if step.action == "navigate":
            nxt = steps[k + 1] if k + 1 < len(steps) else None
            if nxt is None or nxt.object != step.object or nxt.action == "navigate":
                return None
            legs[(name, nxt.action)] = step
            continue
        if (name, step.action) in acts:
            return None
        acts[(name, step.action)] = step
        if step.action == "pick":
            if placing:
                trips.append([])
                placing = False
            trips[-1].append(name)
        else:
            placing = True
    out = []
    for names in trips:
        if any((n, "place") not in acts for n in names):
            return None
        out.append(Trip(tuple(Carry(n, legs.get((n, "pick")), acts[(n, "pick")],
                                    legs.get((n, "place")), acts[(n, "place")])
                              for n in names)))
    if sum(len(t.carries) for t in out) != sum(s.action == "place" for s in steps):
        return None
    return tuple(out)


def split_trip(trip: Trip, capacity: int, fits: Callable[[Sequence[str]], bool]
               ) -> tuple[Trip, ...]:
    """``trip`` cut, in order, into trips of at most ``capacity`` objects whose objects
    ``fits`` says fit on the tray together (a trip of one never needs the tray)."""
    parts: list[list[Carry]] = []
    for c in trip.carries:
        if parts and len(parts[-1]) < capacity \
                and fits([*(p.object for p in parts[-1]), c.object]):
            parts[-1].append(c)
        else:
            parts.append([c])
    return tuple(Trip(tuple(p)) for p in parts)
