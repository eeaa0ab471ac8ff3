"""The place-setting conventions the rater encodes, read from ``conventions.yaml``.

The knowledge (which kind is a fork, what may rest on what, every distance
threshold) lives in the YAML file beside this module; this module only validates
it and gives it types. Lengths are metres, angles degrees, areas square metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field

from llm_grop.datafile import load_yaml_model
from llm_grop.errors import BadInput

_Pair = tuple[float, float]


class _Thresholds(BaseModel):
    model_config = ConfigDict(extra="forbid")

    overlap_area_m2: float = Field(ge=0)
    off_table_overhang_fraction: float = Field(gt=0, le=1)
    overhang_tolerance_m: float = Field(ge=0)
    centre_x_ok_m: float = Field(ge=0)
    centre_x_minor_m: float = Field(ge=0)
    rim_gap_ok_m: _Pair
    rim_gap_minor_m: float = Field(ge=0)
    parallel_tol_deg: float = Field(ge=0, le=90)
    crosswise_deg: float = Field(ge=0, le=90)
    bottoms_spread_m: float = Field(ge=0)
    bottom_to_rim_ok_m: float = Field(ge=0)
    bottom_to_rim_major_m: float = Field(ge=0)
    plate_gap_m: _Pair
    neighbour_gap_m: _Pair
    max_per_side: int = Field(ge=1)
    setting_gap_max_m: float = Field(ge=0)


class _Centre(BaseModel):
    model_config = ConfigDict(extra="forbid")

    preferred: list[str]
    fallback_roles: list[str]


class _ConventionsModel(BaseModel):
    model_config = ConfigDict(extra="forbid")

    roles: dict[str, list[str]]
    centre: _Centre
    order: list[tuple[str, str]]
    supports: dict[str, list[str]]
    expected_stacks: dict[str, list[list[str]]]
    thresholds: _Thresholds


@dataclass(frozen=True)
class Thresholds:
    """Distance, angle and area limits of the rules (metres, degrees, square metres).

    See ``conventions.yaml`` for what each one bounds.
    """

    overlap_area_m2: float
    off_table_overhang_fraction: float
    overhang_tolerance_m: float
    centre_x_ok_m: float
    centre_x_minor_m: float
    rim_gap_ok_m: _Pair
    rim_gap_minor_m: float
    parallel_tol_rad: float
    crosswise_rad: float
    bottoms_spread_m: float
    bottom_to_rim_ok_m: float
    bottom_to_rim_major_m: float
    plate_gap_m: _Pair
    neighbour_gap_m: _Pair
    max_per_side: int
    setting_gap_max_m: float


@dataclass(frozen=True)
class Conventions:
    """The conventions of one diner's place setting, as data.

    ``roles`` maps a role (``fork``, ``drink``, ...) to catalog kinds; ``order``
    holds ``(outer, inner)`` utensil pairs; ``supports`` maps a kind to the kinds
    it may rest on; ``expected_stacks`` maps a kind to groups of supports tried in
    order (see :meth:`expected_groups`).
    """

    roles: dict[str, frozenset[str]]
    centre_preferred: tuple[str, ...]
    centre_fallback_roles: tuple[str, ...]
    order: tuple[tuple[str, str], ...]
    supports: dict[str, frozenset[str]]
    expected_stacks: dict[str, tuple[frozenset[str], ...]]
    thresholds: Thresholds

    def has_role(self, kind: str, role: str) -> bool:
        """Whether catalog kind ``kind`` plays ``role`` (unknown roles: never)."""
        return kind in self.roles.get(role, frozenset())

    def may_rest_on(self, kind: str, support_kind: str) -> bool:
        """Whether an object of ``kind`` may rest on one of ``support_kind``."""
        return support_kind in self.supports.get(kind, frozenset())

    def expected_groups(self, kind: str) -> tuple[frozenset[str], ...]:
        """Support kinds ``kind`` should rest on, best group first (empty: no rule)."""
        return self.expected_stacks.get(kind, ())


#: The conventions file shipped beside this module.
PACKAGED = "conventions.yaml"


def parse_conventions(text: str, where: str) -> Conventions:
    """:class:`Conventions` from YAML ``text``; :class:`BadInput` names the bad field."""
    m = load_yaml_model(text, where, _ConventionsModel, "roles", "name", BadInput)
    t = m.thresholds
    for role in m.centre.fallback_roles:
        if role not in m.roles:
            raise BadInput(f"{where}: centre.fallback_roles: unknown role {role!r}")
    return Conventions(
        roles={r: frozenset(kinds) for r, kinds in m.roles.items()},
        centre_preferred=tuple(m.centre.preferred),
        centre_fallback_roles=tuple(m.centre.fallback_roles),
        order=tuple(m.order),
        supports={k: frozenset(v) for k, v in m.supports.items()},
        expected_stacks={k: tuple(frozenset(g) for g in groups)
                         for k, groups in m.expected_stacks.items()},
        thresholds=Thresholds(
            overlap_area_m2=t.overlap_area_m2,
            off_table_overhang_fraction=t.off_table_overhang_fraction,
            overhang_tolerance_m=t.overhang_tolerance_m,
            centre_x_ok_m=t.centre_x_ok_m, centre_x_minor_m=t.centre_x_minor_m,
            rim_gap_ok_m=t.rim_gap_ok_m, rim_gap_minor_m=t.rim_gap_minor_m,
            parallel_tol_rad=math.radians(t.parallel_tol_deg),
            crosswise_rad=math.radians(t.crosswise_deg),
            bottoms_spread_m=t.bottoms_spread_m,
            bottom_to_rim_ok_m=t.bottom_to_rim_ok_m,
            bottom_to_rim_major_m=t.bottom_to_rim_major_m,
            plate_gap_m=t.plate_gap_m, neighbour_gap_m=t.neighbour_gap_m,
            max_per_side=t.max_per_side, setting_gap_max_m=t.setting_gap_max_m,
        ),
    )


@cache
def load_conventions(path: str | None = None) -> Conventions:
    """The packaged conventions, or those of the YAML file at ``path``."""
    if path is None:
        text = resources.files("llm_grop.evaluation").joinpath(PACKAGED).read_text("utf-8")
        return parse_conventions(text, f"llm_grop/evaluation/{PACKAGED}")
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise BadInput(f"conventions {path}: cannot read ({exc.strerror})") from None
    return parse_conventions(text, f"conventions {path}")
