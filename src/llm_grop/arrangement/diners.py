"""Several diners: one setting per diner, each arranged in that diner's own place.

The LLM is asked once per *distinct* setting (the same kinds in the same order), in the
names of one diner; its relations, gaps and the diner's distance are then given to every
diner with that setting, renamed to their objects ("dinner plate 2" for the second
diner's plate). Each diner's setting is laid out and sampled in their place's frame
(:mod:`llm_grop.geometry.places`): what the LLM calls "to the left of" is to that diner's
left. The k-th configuration of the whole table joins every diner's k-th configuration,
turned into the table frame. Nothing here knows any place-setting convention.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from shapely.geometry import Polygon

from llm_grop import seeds
from llm_grop.arrangement.sampling import violations
from llm_grop.arrangement.setting import Sampled, Setting
from llm_grop.errors import BadInput, Infeasible, NoArrangement
from llm_grop.geometry.places import Place, default_seats, places
from llm_grop.world.angles import wrap_angle
from llm_grop.world.arrangement import Configuration, Item, Placement
from llm_grop.world.catalog import Catalog
from llm_grop.world.fidelity import Fidelity, GapFidelity
from llm_grop.world.relation import Relation
from llm_grop.world.request import for_diners, items_from_names
from llm_grop.world.table import Table

#: ``ask(base_items, place_box)``: the setting the LLM and the preferences give.
Ask = Callable[[Sequence[Item], Table], Setting]
#: ``sample(items, setting, box, rng_factory, region)``: one diner's sampled setting.
Sample = Callable[[Sequence[Item], Setting, Table, Callable[[], np.random.Generator],
                   Polygon | None], Sampled]
#: ``reach(configurations)``: the failure when every joined configuration (table frame)
#: puts an object out of the robot's reach, else ``None``.
Reach = Callable[[Sequence[Configuration]], NoArrangement | None]
#: ``revise(items, setting, box, failure)``: a revision of a setting no configuration in
#: ``box`` keeps (the feedback loop's), or ``None``.
Revise = Callable[[Sequence[Item], Setting, Table, NoArrangement], Setting | None]


@dataclass(frozen=True)
class Diners:
    """Every diner's setting arranged: per diner the (renamed) setting and its sample, the
    distinct settings the LLM was asked about, and the joined configurations (table
    frame) with their fidelity."""

    settings: tuple[Setting, ...]
    sampled: tuple[Sampled, ...]
    distinct: tuple[Setting, ...]
    configurations: tuple[Configuration, ...]
    fidelity: tuple[Fidelity, ...]


def diner_groups(items: Sequence[Item]) -> list[tuple[Item, ...]]:
    """The items of each diner, by diner index (every item must have one)."""
    shared = [it.name for it in items if it.diner is None]
    if shared:
        raise BadInput(f"objects shared by several diners are not supported yet: "
                       f"{', '.join(shared[:3])}")
    count = max(it.diner for it in items if it.diner is not None) + 1
    groups = [tuple(it for it in items if it.diner == k) for k in range(count)]
    empty = [k for k, g in enumerate(groups) if not g]
    if empty:
        raise BadInput(f"diner {empty[0]} has no objects")
    return groups


def seat_items(items: Sequence[Item], table: Table) -> tuple[Item, ...]:
    """``items`` as every seated diner's setting when ``table`` lists its seats and the
    request asked for one setting (one listed seat: that diner's, wherever it is);
    unchanged otherwise."""
    if table.diners and all(it.diner is None for it in items):
        if len(table.diners) == 1:
            return tuple(replace(it, diner=0) for it in items)
        return for_diners(items, len(table.diners))
    return tuple(items)


def seat_table(table: Table, items: Sequence[Item]) -> Table:
    """``table`` with a seat for every diner of ``items``: its own ``diners`` if it lists
    them, else :func:`~llm_grop.geometry.places.default_seats`; unchanged for one diner.
    Raises :class:`BadInput` when the diners plainly do not fit (see :func:`check_fit`)."""
    if all(it.diner is None for it in items):
        return table
    count = len(diner_groups(items))
    if not table.diners:
        table = table.with_diners(default_seats(table, count))
    check_fit(items, table)
    return table


def check_fit(items: Sequence[Item], table: Table) -> None:
    """:class:`BadInput` when the diners plainly cannot all be served at ``table``: a place
    smaller than its setting's footprint or than its largest object. Cheap; run it
    before any LLM call."""
    groups = diner_groups(items)
    seats = table.seats
    if len(seats) != len(groups):
        raise BadInput(f"{len(groups)} diners' settings but {len(seats)} seats at the "
                       f"{table.label}")
    for k, (group, place) in enumerate(zip(groups, places(table, seats), strict=True)):
        area = place.region.area if place.region is not None else place.box.area
        need = sum(it.spec.area for it in group)
        widest = max(group, key=lambda it: min(it.spec.size))
        if need > area or min(widest.spec.size) > min(place.box.width, place.box.depth):
            raise BadInput(f"{len(groups)} diners do not fit at the {table.label}: diner {k}'s "
                           f"place is {place.box.width:.2f} x {place.box.depth:.2f} m for "
                           f"{need:.3f} m² of tableware")


def _renamed(setting: Setting, names: dict[str, str]) -> Setting:
    """``setting`` in another diner's object names."""
    def rel(r: Relation) -> Relation:
        return replace(r, subject=names[r.subject],
                       reference=None if r.reference is None else names[r.reference])
    key = {r.key(): rel(r).key() for r in setting.relations}
    return replace(setting, relations=tuple(rel(r) for r in setting.relations),
                   gaps={key.get(k, k): v for k, v in setting.gaps.items()},
                   origin=names[setting.origin], attempts=(), dropped=(), warnings=())


def _to_table(config: Configuration, place: Place, diner: int) -> list[Placement]:
    out = []
    for p in config.placements:
        x, y = place.to_table(p.x, p.y)
        out.append(replace(p, x=float(x), y=float(y), yaw=wrap_angle(p.yaw + place.yaw),
                           diner=diner))
    return out


def _joined(fidelity: Sequence[Fidelity]) -> Fidelity:
    """Several diners' fidelity as one: every gap, the origins' summed shift, and the
    diner's distance farthest from what was stated."""
    gaps: tuple[GapFidelity, ...] = tuple(g for f in fidelity for g in f.gaps)
    stated = [f for f in fidelity if f.edge_stated_m is not None
              and f.edge_realised_m is not None]
    worst = max(stated, key=lambda f: abs(f.edge_realised_m - f.edge_stated_m),  # type: ignore[operator]
                default=None)
    return Fidelity(gaps, ", ".join(f.origin for f in fidelity),
                    sum(f.origin_shift_m for f in fidelity),
                    None if worst is None else worst.edge_stated_m,
                    None if worst is None else worst.edge_realised_m)


def arrange_diners(items: Sequence[Item], table: Table, catalog: Catalog, seed: int,
                   say: Callable[[str], None], ask: Ask, sample: Sample,
                   revise: Revise | None = None, reach: Reach | None = None) -> Diners:
    """Every diner's setting (see the module doc). When no configuration of a diner's
    setting fits their place, or ``reach`` finds every joined configuration puts one of
    their objects out of the robot's reach, ``revise`` may give a revision of that
    distinct setting (in its first diner's names); every diner is then sampled again (out
    of reach with no revision, the configurations stand: planning says why). Raises
    :class:`BadInput` when a diner's setting does not fit in their place."""
    check_fit(items, table)
    groups = diner_groups(items)
    seated = places(table, table.seats)
    distinct: dict[tuple[str, ...], tuple[tuple[Item, ...], Setting]] = {}
    while True:
        settings, sampled = _sample_all(groups, seated, distinct, catalog, seed, say, ask,
                                        sample, revise, table)
        if settings is None:
            continue
        m = min(len(s.configurations) for s in sampled)
        configs = tuple(Configuration(tuple(
            p for k, (s, place) in enumerate(zip(sampled, seated, strict=True))
            for p in _to_table(s.configurations[c], place, k))) for c in range(m))
        failure = None if reach is None or revise is None else reach(configs)
        if failure is not None:
            k = next(k for k, group in enumerate(groups)
                     if any(it.name in failure.objects for it in group))
            kinds = tuple(it.kind for it in groups[k])
            base, setting = distinct[kinds]
            names = {b.name: g.name for b, g in zip(base, groups[k], strict=True)}
            revised = revise(base, setting, seated[k].box, _in_base_names(failure, names))
            if revised is not None:
                distinct[kinds] = (base, revised)
                continue
        fid = tuple(_joined([s.fidelity[c] for s in sampled]) for c in range(m))
        return Diners(tuple(settings), tuple(sampled), tuple(s for _, s in distinct.values()),
                      configs, fid)


def _sample_all(groups: Sequence[tuple[Item, ...]], seated: Sequence[Place],
                distinct: dict[tuple[str, ...], tuple[tuple[Item, ...], Setting]],
                catalog: Catalog, seed: int, say: Callable[[str], None], ask: Ask,
                sample: Sample, revise: Revise | None, table: Table
                ) -> tuple[list[Setting] | None, list[Sampled]]:
    """Every diner's renamed setting and sample; ``(None, ...)`` when a diner's distinct
    setting was revised on the way (``distinct`` holds the revision: sample them all
    again)."""
    settings, sampled = [], []
    for k, (group, place) in enumerate(zip(groups, seated, strict=True)):
        kinds = tuple(it.kind for it in group)
        if kinds not in distinct:
            base = items_from_names(kinds, catalog)
            distinct[kinds] = (base, ask(base, place.box))
        base, setting = distinct[kinds]
        names = {b.name: g.name for b, g in zip(base, group, strict=True)}
        mine = _renamed(setting, names)
        say(f"sampling configurations for diner {k + 1} of {len(groups)}")
        try:
            one = sample(group, mine, place.box,
                         lambda k=k: seeds.stream(seed, "sampler", k), place.region)
        except NoArrangement as exc:
            revised = None if revise is None else \
                revise(base, setting, place.box, _in_base_names(exc, names))
            if revised is None:
                raise _no_fit(len(groups), table, k, place, exc) from None
            distinct[kinds] = (base, revised)
            return None, sampled
        except Infeasible as exc:
            raise _no_fit(len(groups), table, k, place, exc) from None
        settings.append(mine)
        sampled.append(one)
    return settings, sampled


def _no_fit(n: int, table: Table, k: int, place: Place, exc: Infeasible) -> BadInput:
    """The error for diner ``k``'s setting that does not fit their place."""
    return BadInput(f"{n} diners do not fit at the {table.label}: diner {k}'s place "
                    f"({place.box.width:.2f} x {place.box.depth:.2f} m) cannot hold the "
                    f"setting ({exc})")


def _in_base_names(exc: NoArrangement, names: dict[str, str]) -> NoArrangement:
    """``exc`` (of its own class) in the first diner's object names (``names`` maps them
    to this diner's)."""
    back = {mine: base for base, mine in names.items()}
    why, detail = exc.why, exc.detail
    for mine in sorted(back, key=len, reverse=True):
        why, detail = why.replace(mine, back[mine]), detail.replace(mine, back[mine])
    return type(exc)(detail, tuple(back.get(o, o) for o in exc.objects), why)


def in_place_frames(placements: Sequence[Placement], table: Table
                    ) -> list[tuple[Place, list[Placement]]]:
    """Each diner's place and their placements in its frame (``diner`` ``None``: the one
    diner of a table without ``diners``)."""
    seated = places(table, table.seats)
    out: list[tuple[Place, list[Placement]]] = []
    for k, place in enumerate(seated):
        mine = [p for p in placements if (p.diner or 0) == k]
        local = []
        for p in mine:
            x, y = place.to_place(p.x, p.y)
            local.append(replace(p, x=float(x), y=float(y), yaw=wrap_angle(p.yaw - place.yaw)))
        out.append((place, local))
    return out


def violations_at_table(config: Configuration, relations: Sequence[Relation],
                        table: Table) -> list[str]:
    """:func:`~llm_grop.arrangement.sampling.violations` with every diner's relations
    judged in that diner's place frame (one diner: in the table frame, as always)."""
    if len(table.seats) == 1 or all(p.diner is None for p in config.placements):
        return violations(config, relations, table)
    diner_of = {p.name: p.diner for p in config.placements}
    out: list[str] = []
    for k, (place, local) in enumerate(in_place_frames(config.placements, table)):
        names = {p.name for p in local}
        mine = [r for r in relations if diner_of.get(r.subject) == k
                and (r.reference is None or r.reference in names)]
        out += violations(Configuration(tuple(local)), mine, place.box, place.region)
    return out

