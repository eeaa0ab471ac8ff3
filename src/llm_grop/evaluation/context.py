"""What the rater's rules share: the centre object, the cutlery, and check helpers.

Lengths are metres (details print centimetres); see docs/rater.md for the terms
(level, centre object, cutlery).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from llm_grop.evaluation.model import Check, Obj, Setting, Severity

#: A crosswise dessert utensil lies above the centre object: its centre at most this far
#: (metres) below the centre object's far rim.
_DESSERT_SLACK_M = 0.03

Issue = tuple[Severity, str]


def cm(metres: float) -> str:
    """``metres`` as centimetres with one decimal, for details."""
    return f"{metres * 100:.1f} cm"


def pos(o: Obj) -> str:
    """``o``'s centre as ``(x, y) m``, for details."""
    return f"({o.x:+.3f}, {o.y:+.3f}) m"


def outcome(name: str, severity: Severity, issues: Sequence[Issue], ok: str) -> list[Check]:
    """One passed check (detail ``ok``) or one failed check per issue."""
    if not issues:
        return [Check(name, True, severity, ok)]
    return [Check(name, False, sev, detail) for sev, detail in issues]


def skipped(name: str, severity: Severity, why: str) -> list[Check]:
    """A skipped check: the rule's reference object is absent (``why``)."""
    return [Check(name, True, severity, why, skipped=True)]


@dataclass(frozen=True)
class Context:
    """What several rules share: the centre object and the cutlery beside it."""

    centre: Obj | None
    #: Utensils lying on the table beside the setting (not dessert cutlery, not an
    #: object the conventions want on a support that is present).
    cutlery: tuple[Obj, ...]

    def side_of(self, o: Obj) -> str:
        """``"left"`` or ``"right"`` of the centre object's centre line."""
        assert self.centre is not None
        return "left" if o.x < self.centre.x else "right"


def find_centre(s: Setting) -> Obj | None:
    """The centre object: the first preferred kind present, else the largest plate or bowl.

    Objects resting on the table are preferred over stacked ones.
    """
    table_level = [o for o in s.objects if s.on_table(o)]
    for pool in (table_level, list(s.objects)):
        for kind in s.conv.centre_preferred:
            for o in pool:
                if o.kind == kind:
                    return o
        candidates = [o for o in pool
                      if any(s.conv.has_role(o.kind, r) for r in s.conv.centre_fallback_roles)]
        if candidates:
            return max(candidates, key=lambda o: o.footprint.area)
    return None


def _has_free_host(s: Setting, o: Obj, group: frozenset[str]) -> list[Obj]:
    """Objects of ``group`` that ``o`` could rest on (not carrying another of its kind)."""
    hosts = []
    for h in s.objects:
        if h is o or h.kind not in group:
            continue
        taken = any(other is not o and other.kind == o.kind and s.support[other.name] == h.name
                    for other in s.objects)
        if not taken or s.support[o.name] == h.name:
            hosts.append(h)
    return hosts


def expected_hosts(s: Setting, o: Obj) -> tuple[int, list[Obj]] | None:
    """``(group index, hosts)`` of the first expected-support group present for ``o``."""
    for k, group in enumerate(s.conv.expected_groups(o.kind)):
        hosts = _has_free_host(s, o, group)
        if hosts:
            return k, hosts
    return None


def _on_napkin(s: Setting, o: Obj) -> bool:
    """Whether ``o`` rests on a napkin (a fork on its napkin is still a fork at its side)."""
    host = s.support[o.name]
    return host is not None and s.conv.has_role(s.by_name(host).kind, "napkin")


def make_context(s: Setting) -> Context:
    """The centre object and the cutlery of ``s``."""
    centre = find_centre(s)
    tol = s.conv.thresholds.parallel_tol_rad
    cutlery = []
    for o in s.objects:
        if not (s.on_table(o) or _on_napkin(s, o)) or not any(
                s.conv.has_role(o.kind, r) for r in ("fork", "knife", "spoon")):
            continue
        if expected_hosts(s, o) is not None:
            continue  # e.g. a butter knife with a bread plate present: judged by `stacking`
        if centre is not None and s.conv.has_role(o.kind, "dessert"):
            c = centre.bounds
            crosswise = o.axis_deviation() >= math.pi / 2 - tol
            if crosswise and o.y >= c[3] - _DESSERT_SLACK_M and c[0] <= o.x <= c[2]:
                continue  # dessert cutlery lying across, above the plate
        cutlery.append(o)
    return Context(centre, tuple(cutlery))
