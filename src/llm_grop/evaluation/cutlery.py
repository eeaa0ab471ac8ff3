"""The rater's cutlery rules: sides, order, angle, alignment and spacing beside the plate.

Forks go left of the centre object, knives and spoons right; cutlery lies along
the line of sight with aligned bottom ends near the plate's lower rim, about
1-3 cm from the plate and 1 cm apart (design/place-setting.md, "Cutlery").
Lengths are metres, angles radians; thresholds come from ``conventions.yaml``.
"""

from __future__ import annotations

import math
from collections import Counter

from llm_grop.evaluation.context import Context, Issue, cm, outcome, skipped
from llm_grop.evaluation.model import Check, Obj, Setting, Severity


def _wanted_side(s: Setting, o: Obj) -> str:
    return "left" if s.conv.has_role(o.kind, "fork") else "right"


def _plural(s: Setting, o: Obj) -> str:
    for role, word in (("fork", "forks"), ("knife", "knives"), ("spoon", "spoons")):
        if s.conv.has_role(o.kind, role):
            return word
    return "utensils"


def cutlery_sides(s: Setting, ctx: Context) -> list[Check]:
    """Forks left of the centre object; knives and spoons right of it."""
    c = ctx.centre
    if not ctx.cutlery:
        return skipped("cutlery sides", "major", "no cutlery on the table")
    if c is None:
        return skipped("cutlery sides", "major", "no centre object to take sides of")
    issues: list[Issue] = []
    for o in ctx.cutlery:
        want, got = _wanted_side(s, o), ctx.side_of(o)
        if want != got:
            issues.append(("major", f"{o.name} at x = {o.x:+.3f} m lies {got} of the {c.name} "
                           f"(x = {c.x:+.3f} m); {_plural(s, o)} go on the {want}"))
    return outcome("cutlery sides", "major", issues,
                    f"forks left, knives and spoons right of the {c.name}")


def _correct_side(s: Setting, ctx: Context, side: str) -> list[Obj]:
    """Cutlery on ``side`` that belongs there, nearest the centre object first."""
    assert ctx.centre is not None
    cx = ctx.centre.x
    objs = [o for o in ctx.cutlery if _wanted_side(s, o) == side and ctx.side_of(o) == side]
    return sorted(objs, key=lambda o: abs(o.x - cx))


def cutlery_order(s: Setting, ctx: Context) -> list[Check]:
    """Outer utensils outside: salad fork left of dinner fork, spoons right of knives."""
    name = "cutlery order"
    c = ctx.centre
    if c is None or not ctx.cutlery:
        return skipped(name, "minor", "no cutlery beside a centre object")
    issues: list[Issue] = []
    judged = 0
    for side in ("left", "right"):
        objs = _correct_side(s, ctx, side)
        for outer_kind, inner_kind in s.conv.order:
            for a in (o for o in objs if o.kind == outer_kind):
                for b in (o for o in objs if o.kind == inner_kind):
                    judged += 1
                    da, db = abs(a.x - c.x), abs(b.x - c.x)
                    if da <= db:
                        issues.append(("minor", f"{a.name} lies inside the {b.name} "
                                       f"({cm(da)} vs {cm(db)} from the {c.name}'s centre); "
                                       f"the {outer_kind} goes outside"))
    if not judged:
        return skipped(name, "minor", "no pair of utensils whose order is set")
    return outcome(name, "minor", issues, "outer utensils lie outside the inner ones")


def pieces_per_side(s: Setting, ctx: Context) -> list[Check]:
    """At most three utensils on each side of the plate."""
    t = s.conv.thresholds
    if ctx.centre is None or not ctx.cutlery:
        return skipped("pieces per side", "minor", "no cutlery beside a centre object")
    counts = Counter(ctx.side_of(o) for o in ctx.cutlery)
    issues: list[Issue] = [("minor", f"{n} utensils on the {side}; at most {t.max_per_side}")
                           for side, n in sorted(counts.items()) if n > t.max_per_side]
    return outcome("pieces per side", "minor", issues,
                    f"{counts['left']} left, {counts['right']} right "
                    f"(at most {t.max_per_side} a side)")


def cutlery_parallel(s: Setting, ctx: Context) -> list[Check]:
    """Cutlery lies along the line of sight (yaw near 0 or pi)."""
    t = s.conv.thresholds
    if not ctx.cutlery:
        return skipped("cutlery parallel", "major", "no cutlery on the table")
    issues: list[Issue] = []
    for o in ctx.cutlery:
        dev = o.axis_deviation()
        if dev > t.parallel_tol_rad:
            sev: Severity = "minor" if dev <= t.crosswise_rad else "major"
            issues.append((sev, f"{o.name} is turned {math.degrees(dev):.0f}° from the line "
                           f"of sight (at most {math.degrees(t.parallel_tol_rad):.0f}°)"))
    return outcome("cutlery parallel", "major", issues,
                    "all cutlery within "
                    f"{math.degrees(t.parallel_tol_rad):.0f}° of the line of sight")


def bottoms_aligned(s: Setting, ctx: Context) -> list[Check]:
    """The bottom ends of the cutlery line up."""
    t = s.conv.thresholds
    if len(ctx.cutlery) < 2:
        return skipped("cutlery bottoms aligned", "minor", "fewer than two utensils")
    bottoms = {o.name: o.bottom for o in ctx.cutlery}
    spread = max(bottoms.values()) - min(bottoms.values())
    listing = ", ".join(f"{n} {b:+.3f}" for n, b in bottoms.items())
    detail = (f"bottom ends at y = {listing} m: spread {cm(spread)} "
              f"(at most {cm(t.bottoms_spread_m)})")
    issues: list[Issue] = [("minor", detail)] if spread > t.bottoms_spread_m else []
    return outcome("cutlery bottoms aligned", "minor", issues, detail)


def near_rim(s: Setting, ctx: Context) -> list[Check]:
    """Each utensil's bottom end is near the centre object's lower rim (beside the plate)."""
    t = s.conv.thresholds
    c = ctx.centre
    if c is None or not ctx.cutlery:
        return skipped("cutlery beside plate", "major", "no cutlery beside a centre object")
    issues: list[Issue] = []
    for o in ctx.cutlery:
        d = abs(o.bottom - c.bottom)
        if d > t.bottom_to_rim_ok_m:
            sev: Severity = "minor" if d <= t.bottom_to_rim_major_m else "major"
            issues.append((sev, f"{o.name}'s bottom end (y = {o.bottom:+.3f} m) is {cm(d)} "
                           f"from the {c.name}'s lower rim (y = {c.bottom:+.3f} m); at most "
                           f"{cm(t.bottom_to_rim_ok_m)}"))
    return outcome("cutlery beside plate", "major", issues,
                    f"all bottom ends within {cm(t.bottom_to_rim_ok_m)} of the {c.name}'s "
                    "lower rim")


def plate_gap(s: Setting, ctx: Context) -> list[Check]:
    """About 1-3 cm between the centre object and the nearest utensil on each side."""
    t = s.conv.thresholds
    c = ctx.centre
    if c is None or not ctx.cutlery:
        return skipped("plate gap", "minor", "no cutlery beside a centre object")
    lo, hi = t.plate_gap_m
    issues: list[Issue] = []
    found = []
    for side in ("left", "right"):
        objs = _correct_side(s, ctx, side)
        if not objs:
            continue
        nearest = min(objs, key=lambda o: o.footprint.distance(c.footprint))
        gap = nearest.footprint.distance(c.footprint)
        found.append(f"{nearest.name} {cm(gap)}")
        if not lo <= gap <= hi:
            issues.append(("minor", f"{nearest.name} is {cm(gap)} from the {c.name} "
                           f"(nominal 1-3 cm, {cm(lo)}-{cm(hi)} tolerated)"))
    if not found:
        return skipped("plate gap", "minor", "no utensil on its proper side")
    return outcome("plate gap", "minor", issues, "gaps to the plate: " + ", ".join(found))


def utensil_spacing(s: Setting, ctx: Context) -> list[Check]:
    """About 1 cm between neighbouring utensils on the same side."""
    t = s.conv.thresholds
    lo, hi = t.neighbour_gap_m
    if ctx.centre is None:
        return skipped("utensil spacing", "minor", "no centre object")
    issues: list[Issue] = []
    found = []
    for side in ("left", "right"):
        objs = _correct_side(s, ctx, side)
        for a, b in zip(objs, objs[1:], strict=False):
            gap = a.footprint.distance(b.footprint)
            found.append(f"{a.name}-{b.name} {cm(gap)}")
            if not lo <= gap <= hi:
                issues.append(("minor", f"{a.name} and {b.name} are {cm(gap)} apart "
                               f"(about 1 cm; {cm(lo)}-{cm(hi)} tolerated)"))
    if not found:
        return skipped("utensil spacing", "minor", "no two utensils on the same side")
    return outcome("utensil spacing", "minor", issues, "neighbour gaps: " + ", ".join(found))
