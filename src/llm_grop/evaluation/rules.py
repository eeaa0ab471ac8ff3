"""The rater's rules: each turns a :class:`~llm_grop.evaluation.model.Setting` into checks.

Every rule returns one passed :class:`Check` when nothing is wrong, one failed
check per fault otherwise (each naming the objects and measured values), or one
skipped check when the object it needs is absent. Thresholds come from
``conventions.yaml``; lengths are metres (details print centimetres), angles
radians (details print degrees). docs/rater.md lists every rule; the cutlery rules are in
:mod:`llm_grop.evaluation.cutlery`.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable

import shapely
from shapely.geometry import Point
from shapely.geometry.base import BaseGeometry

from llm_grop.evaluation.context import (
    Context,
    Issue,
    cm,
    expected_hosts,
    outcome,
    pos,
    skipped,
)
from llm_grop.evaluation.cutlery import (
    bottoms_aligned,
    cutlery_order,
    cutlery_parallel,
    cutlery_sides,
    near_rim,
    pieces_per_side,
    plate_gap,
    utensil_spacing,
)
from llm_grop.evaluation.model import Check, Obj, Setting, Severity
from llm_grop.world.arrangement import UPRIGHT_TILT_RAD

#: How far (metres) outside its support a stacked object's centre may lie.
_STACK_SLACK_M = 0.005


# --- presence and the table -----------------------------------------------------------

def items_present(s: Setting, ctx: Context) -> list[Check]:
    """Every requested item is there (a missing one scores 1)."""
    name = "all items present"
    if s.requested is None:
        return skipped(name, "missing", "no request to compare with")
    want, have = Counter(s.requested), Counter(o.kind for o in s.objects if o.upright)
    issues: list[Issue] = [
        ("missing", f"{kind} missing (requested {n}, found {have[kind]})")
        for kind, n in want.items() if have[kind] < n]
    extra = sorted(set(have) - set(want))
    more = f"; also on the table: {', '.join(extra)}" if extra else ""
    return outcome(name, "missing", issues,
                    f"all {sum(want.values())} requested items present{more}")


def upright(s: Setting, ctx: Context) -> list[Check]:
    """Every object stands upright: one that tipped over counts as not placed."""
    issues: list[Issue] = [
        ("missing", f"{o.name} lies tipped over ({o.tilt_rad:.2f} rad from upright, at most "
                    f"{UPRIGHT_TILT_RAD:.2f}); it counts as not placed")
        for o in s.objects if not o.upright]
    return outcome("upright", "missing", issues, "every object stands upright")


def on_table(s: Setting, ctx: Context) -> list[Check]:
    """Every object stands on the table top; a big overhang counts as off the table."""
    if s.outline is not None:
        return _on_outline(s)
    t = s.conv.thresholds
    w2, d2 = s.width / 2, s.depth / 2
    off: list[Issue] = []
    over_edge: list[Issue] = []
    for o in s.objects:
        minx, miny, maxx, maxy = o.bounds
        overs = {"left": -w2 - minx, "right": maxx - w2,
                 "diner's": -d2 - miny, "far": maxy - d2}
        edge, worst = max(overs.items(), key=lambda kv: kv[1])
        extent = (maxx - minx) if edge in ("left", "right") else (maxy - miny)
        if abs(o.x) > w2 or abs(o.y) > d2:
            off.append(("missing", f"{o.name}: centre {pos(o)} is off the "
                        f"{s.width:.2f} x {s.depth:.2f} m table top"))
        elif worst / extent > t.off_table_overhang_fraction:
            off.append(("missing", f"{o.name} hangs {cm(worst)} ({worst / extent:.0%} of its "
                        f"{cm(extent)}) over the {edge} edge; at most "
                        f"{t.off_table_overhang_fraction:.0%}"))
        elif worst > t.overhang_tolerance_m:
            over_edge.append(("minor", f"{o.name} hangs {cm(worst)} over the {edge} edge"))
    return [*outcome("on table", "missing", off,
                      f"all {len(s.objects)} objects on the {s.width:.2f} x {s.depth:.2f} m top"),
            *outcome("edge overhang", "minor", over_edge,
                      f"nothing hangs more than {cm(t.overhang_tolerance_m)} over an edge")]


def _on_outline(s: Setting) -> list[Check]:
    """:func:`on_table` for a top that is not the setting's rectangle (a round top, a diner's
    place at a bigger table): the overhang is the share of the footprint's area outside
    the top, and how far its farthest point lies beyond the edge."""
    t = s.conv.thresholds
    top = s.outline
    assert top is not None
    off: list[Issue] = []
    over_edge: list[Issue] = []
    for o in s.objects:
        outside = o.footprint.difference(top)
        share = outside.area / o.footprint.area if o.footprint.area > 0 else 0.0
        worst = max((top.exterior.distance(Point(c)) for c in _points(outside)), default=0.0)
        if not top.contains(Point(o.x, o.y)):
            off.append(("missing", f"{o.name}: centre {pos(o)} is off the table top"))
        elif share > t.off_table_overhang_fraction:
            off.append(("missing", f"{o.name} hangs {share:.0%} of its area over the edge; "
                        f"at most {t.off_table_overhang_fraction:.0%}"))
        elif worst > t.overhang_tolerance_m:
            over_edge.append(("minor", f"{o.name} hangs {cm(worst)} over the edge"))
    return [*outcome("on table", "missing", off, f"all {len(s.objects)} objects on the top"),
            *outcome("edge overhang", "minor", over_edge,
                     f"nothing hangs more than {cm(t.overhang_tolerance_m)} over an edge")]


def _points(g: BaseGeometry) -> list[tuple[float, float]]:
    """Every vertex of ``g`` (any polygonal geometry)."""
    return [(float(x), float(y)) for x, y in shapely.get_coordinates(g)]


def overlap(s: Setting, ctx: Context) -> list[Check]:
    """No two objects at the same level (same support) interpenetrate."""
    limit = s.conv.thresholds.overlap_area_m2
    issues: list[Issue] = []
    objs = s.objects
    for i, a in enumerate(objs):
        for b in objs[i + 1:]:
            if s.support[a.name] != s.support[b.name]:
                continue
            area = a.footprint.intersection(b.footprint).area
            if area > limit:
                issues.append(("major", f"{a.name} and {b.name} overlap by "
                               f"{area * 1e4:.1f} cm² (at most {limit * 1e4:.1f} cm²)"))
    return outcome("overlap", "major", issues,
                    f"no footprints at the same level overlap by more than {limit * 1e4:.1f} cm²")


# --- stacking -------------------------------------------------------------------------

def support_allowed(s: Setting, ctx: Context) -> list[Check]:
    """An object rests only on what it may rest on (lid on mug, mug on mat, ...)."""
    issues: list[Issue] = []
    stacked = [o for o in s.objects if s.support[o.name] is not None]
    for o in stacked:
        host = s.by_name(s.support[o.name] or "")
        if not s.conv.may_rest_on(o.kind, host.kind):
            allowed = sorted(s.conv.supports.get(o.kind, ()))
            goes = f"a {o.kind} goes on: {', '.join(allowed)}" if allowed \
                else f"a {o.kind} goes on the table"
            issues.append(("major", f"{o.name} rests on {host.name}; {goes}"))
    if not stacked:
        return skipped("support allowed", "major", "nothing rests on another object")
    pairs = ", ".join(f"{o.name} on {s.support[o.name]}" for o in stacked)
    return outcome("support allowed", "major", issues, f"allowed: {pairs}")


def stack_geometry(s: Setting, ctx: Context) -> list[Check]:
    """An object that is ``on`` another has its centre over that object's footprint."""
    issues: list[Issue] = []
    stacked = [o for o in s.objects if o.on is not None]
    for o in stacked:
        host = s.by_name(o.on or "")
        if not host.footprint.buffer(_STACK_SLACK_M).covers(Point(o.x, o.y)):
            d = math.hypot(o.x - host.x, o.y - host.y)
            issues.append(("major", f"{o.name} is 'on' {host.name} but its centre is "
                           f"{cm(d)} from {host.name}'s, outside its footprint"))
    if not stacked:
        return skipped("stack geometry", "major", "no object names a support in 'on'")
    return outcome("stack geometry", "major", issues,
                    "every stacked object's centre is over its support")


def stacking(s: Setting, ctx: Context) -> list[Check]:
    """Stacks the conventions expect when both objects are present (lid on mug, ...)."""
    issues: list[Issue] = []
    judged = []
    for o in s.objects:
        found = expected_hosts(s, o)
        if found is None:
            continue
        k, hosts = found
        judged.append(o.name)
        below = s.support[o.name]
        below_kind = s.by_name(below).kind if below is not None else None
        where = below or "the table"
        names = " or ".join(h.name for h in hosts)
        if below_kind is not None and below_kind in s.conv.expected_groups(o.kind)[k]:
            continue
        if below_kind is not None and any(below_kind in g
                                          for g in s.conv.expected_groups(o.kind)):
            issues.append(("minor", f"{o.name} rests on {where}; with {names} present it goes "
                           f"on {names}"))
        else:
            issues.append(("major", f"{o.name} rests on {where}; it goes on {names}"))
    if not judged:
        return skipped("stacking", "major", "no pair the conventions stack is present")
    return outcome("stacking", "major", issues,
                    "stacked as expected: " + ", ".join(
                        f"{n} on {s.support[n]}" for n in judged))


# --- the centre of the setting ---------------------------------------------------------

def centre_object(s: Setting, ctx: Context) -> list[Check]:
    """The centre object sits centred in front of the diner, its rim near the edge."""
    t = s.conv.thresholds
    c = ctx.centre
    if c is None:
        return skipped("centre object", "major", "no plate or bowl to centre the setting on")
    dx = abs(c.x)
    rim = c.bottom + s.depth / 2
    lo, hi = t.rim_gap_ok_m
    sev_x: Severity | None = None if dx <= t.centre_x_ok_m else \
        "minor" if dx <= t.centre_x_minor_m else "major"
    sev_rim: Severity | None = None if lo <= rim <= hi else \
        "minor" if rim <= t.rim_gap_minor_m else "major"
    detail = (f"{c.name}: centre x = {c.x:+.3f} m (|x| <= {t.centre_x_ok_m:.2f} m passes), "
              f"near rim {cm(rim)} from the diner's edge ({cm(lo)}-{cm(hi)} passes)")
    sev = "major" if "major" in (sev_x, sev_rim) else "minor" if (sev_x or sev_rim) else None
    return outcome("centre object", "major", [(sev, detail)] if sev else [], detail)


# --- other objects around the centre ----------------------------------------------------

def drinks(s: Setting, ctx: Context) -> list[Check]:
    """Drinks go to the upper right: right of the plate, above it or above the knife tip."""
    c = ctx.centre
    objs = s.with_role("drink")
    if not objs:
        return skipped("drinks upper right", "major", "no drink")
    if c is None:
        return skipped("drinks upper right", "major", "no centre object")
    knives = [o for o in ctx.cutlery if s.conv.has_role(o.kind, "knife")
              and ctx.side_of(o) == "right"]
    tip = max((k.bounds[3] for k in knives), default=None)
    issues: list[Issue] = []
    for o in objs:
        if o.x <= c.x:
            issues.append(("major", f"{o.name} at {pos(o)} is not right of the {c.name} "
                           f"(x = {c.x:+.3f} m); drinks go to the upper right"))
        elif o.y <= c.y and (tip is None or o.bottom < tip):
            issues.append(("minor", f"{o.name} at {pos(o)} is right of the {c.name} but not "
                           f"above it (y <= {c.y:+.3f} m) nor above the knife tip"))
    return outcome("drinks upper right", "major", issues,
                    ", ".join(f"{o.name} {pos(o)}" for o in objs) + f": upper right of {c.name}")


def _placed_around(s: Setting, ctx: Context, role: str) -> list[Obj]:
    return [o for o in s.with_role(role) if o is not ctx.centre and s.on_table(o)]


def bread_plate(s: Setting, ctx: Context) -> list[Check]:
    """The bread plate goes to the upper left, above the forks."""
    c = ctx.centre
    objs = _placed_around(s, ctx, "bread_plate")
    if not objs or c is None:
        return skipped("bread plate upper left", "major",
                     "no bread plate besides the centre object" if not objs else
                     "no centre object")
    issues: list[Issue] = []
    for o in objs:
        if o.x >= c.x:
            issues.append(("major", f"{o.name} at {pos(o)} is not left of the {c.name} "
                           f"(x = {c.x:+.3f} m); it goes to the upper left"))
        elif o.y <= c.y:
            issues.append(("minor", f"{o.name} at {pos(o)} is left of the {c.name} but not "
                           "above it"))
    return outcome("bread plate upper left", "major", issues,
                    ", ".join(f"{o.name} {pos(o)}" for o in objs) + f": upper left of {c.name}")


def bowls(s: Setting, ctx: Context) -> list[Check]:
    """A bowl that is not the centre goes above the plate or to its upper left."""
    c = ctx.centre
    objs = _placed_around(s, ctx, "bowl")
    if not objs or c is None:
        return skipped("bowl position", "major", "no bowl besides the centre object"
                     if not objs else "no centre object")
    issues: list[Issue] = []
    for o in objs:
        if o.y <= c.y:
            issues.append(("major", f"{o.name} at {pos(o)} is not above the {c.name} "
                           f"(y = {c.y:+.3f} m)"))
        elif o.x > c.bounds[2]:
            issues.append(("minor", f"{o.name} at {pos(o)} is to the upper right, where the "
                           "drinks go; bowls go above or to the upper left"))
    return outcome("bowl position", "major", issues,
                    ", ".join(f"{o.name} {pos(o)}" for o in objs) + f": above {c.name}")


def napkin(s: Setting, ctx: Context) -> list[Check]:
    """The napkin goes to the left of the forks, or on the plate."""
    c = ctx.centre
    objs = s.with_role("napkin")
    if not objs or c is None:
        return skipped("napkin position", "major", "no napkin" if not objs else
                     "no centre object")
    forks = [o for o in ctx.cutlery if s.conv.has_role(o.kind, "fork") and o.x < c.x]
    issues: list[Issue] = []
    for o in objs:
        if not s.on_table(o):
            continue  # on the plate, or judged by `support allowed`
        if o.x >= c.x:
            issues.append(("major", f"{o.name} at {pos(o)} is not left of the {c.name} "
                           f"(x = {c.x:+.3f} m); it goes left of the forks or on the plate"))
        elif (apart := [f for f in forks if s.support[f.name] != o.name]) \
                and o.x >= min(f.x for f in apart):
            issues.append(("minor", f"{o.name} at {pos(o)} lies between the forks and the "
                           f"{c.name}; it goes left of the forks"))
    return outcome("napkin position", "major", issues,
                    "napkin left of the forks or on the plate")


def compact(s: Setting, ctx: Context) -> list[Check]:
    """Nothing on the table lies far from the rest of the setting."""
    t = s.conv.thresholds
    objs = [o for o in s.objects if s.on_table(o)]
    if len(objs) < 2:
        return skipped("close to the setting", "minor", "fewer than two objects on the table")
    issues: list[Issue] = []
    for o in objs:
        gap, other = min((o.footprint.distance(p.footprint), p.name) for p in objs if p is not o)
        if gap > t.setting_gap_max_m:
            issues.append(("minor", f"{o.name} is {cm(gap)} from the nearest object "
                           f"({other}); at most {cm(t.setting_gap_max_m)}"))
    return outcome("close to the setting", "minor", issues,
                    f"every object within {cm(t.setting_gap_max_m)} of another")


Rule = Callable[[Setting, Context], list[Check]]

#: Every rule, in the order checks are reported.
RULES: tuple[Rule, ...] = (
    items_present, upright, on_table, overlap, support_allowed, stack_geometry, stacking,
    centre_object, cutlery_sides, cutlery_order, pieces_per_side, cutlery_parallel,
    bottoms_aligned, near_rim, plate_gap, utensil_spacing, drinks, bread_plate, bowls,
    napkin, compact,
)
