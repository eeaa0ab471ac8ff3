"""The typed reading of a request, and the request the pipeline takes from it.

A :class:`Reading` is what a request means, whoever read it (the catalog matcher or an
LLM): the objects with their counts, the diners, the relations it states with any
distances, and where each part came from. :func:`to_request` turns it into the
:class:`~llm_grop.world.request.Request` the arrangement takes: numbered items, definite
relations (``source="request"``) and the ambiguous ones as
:class:`~llm_grop.world.relation.Choice` for the arrangement to decide.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from llm_grop.errors import BadInput
from llm_grop.language.vocabulary import BESIDE, EITHER_SIDE, beside, either_side
from llm_grop.world.catalog import Catalog
from llm_grop.world.llmlog import CallRecord
from llm_grop.world.relation import CENTER, Choice, Relation
from llm_grop.world.request import MAX_COUNT, MAX_DINERS, Request, Wanted, for_diners, number_items


@dataclass(frozen=True)
class ReadObject:
    """``count`` of catalog kind ``name`` (per diner). ``source``: ``"request"`` when the
    request names it with its number, ``"llm"`` when the LLM chose it (or how many);
    ``words``: the request's words it was read from."""

    name: str
    count: int
    source: str = "request"
    words: str = ""


@dataclass(frozen=True)
class ReadRelation:
    """A relation the request states. ``subject``, ``reference`` and ``partner`` are item
    names ("dinner fork", "dinner fork 2"); ``relation`` is a relation name or an ambiguous
    word (``beside``; ``either side of``, whose second subject is ``partner``);
    ``reference`` is ``None`` for ``center``. ``distance_cm`` is a stated gap between the
    objects' edges, centimetres; ``words`` the request's words that state it."""

    subject: str
    relation: str
    reference: str | None
    distance_cm: float | None = None
    partner: str | None = None
    words: str = ""

    def meaning(self) -> tuple[str, str, str | None, float | None, str | None]:
        """What the relation says, without the words it was said in."""
        cm = None if self.distance_cm is None else round(self.distance_cm, 4)
        if self.relation == EITHER_SIDE and self.partner is not None:
            # Either side of is symmetric in its two objects.
            a, b = sorted((self.subject, self.partner))
            return (a, self.relation, self.reference, cm, b)
        return (self.subject, self.relation, self.reference, cm, self.partner)


@dataclass(frozen=True)
class Reading:
    """What a request means: ``objects`` in order of first mention (one diner's setting),
    the ``relations`` it states, how many ``diners``, and who read it (``read_by``:
    ``"catalog"``, the matcher alone; ``"llm"``, an LLM)."""

    text: str
    objects: tuple[ReadObject, ...]
    relations: tuple[ReadRelation, ...] = ()
    diners: int = 1
    read_by: str = "catalog"

    def meaning(self) -> tuple[object, ...]:
        """What the reading says, without who read it or the words: two readers agree
        when their meanings are equal."""
        return (self.diners, tuple((o.name, o.count, o.source) for o in self.objects),
                tuple(sorted((r.meaning() for r in self.relations), key=repr)))

    @property
    def guessed(self) -> tuple[str, ...]:
        """The kinds the LLM chose that the request does not name (or not how many)."""
        return tuple(dict.fromkeys(o.name for o in self.objects if o.source == "llm"))


def item_names(objects: Sequence[ReadObject], catalog: Catalog) -> list[str]:
    """The item names of one diner's ``objects``, numbered as the request's items are."""
    items, _ = number_items([Wanted(catalog.specs[o.name], o.count) for o in objects])
    return [it.name for it in items]


def check_reading(reading: Reading, catalog: Catalog, where: str = "request") -> None:
    """Raises :class:`BadInput` (one line naming ``where``) unless ``reading`` is one the
    pipeline can take: objects of the catalog, counts and diners of 1 to 12, relations
    between objects of the reading (see :func:`unrelated`), and distances that are not
    negative."""
    if not reading.objects:
        raise BadInput(f"{where}: no object named in {reading.text!r}; name the objects to "
                       "set, e.g. 'a dinner plate, a dinner fork and a dinner knife'")
    if not 1 <= reading.diners <= MAX_DINERS:
        raise BadInput(f"{where}: {reading.diners} diners; between 1 and {MAX_DINERS}")
    for o in reading.objects:
        if o.name not in catalog.specs:
            raise BadInput(f"{where}: {o.name!r} is no catalog name")
        if not 1 <= o.count <= MAX_COUNT:
            raise BadInput(f"{where}: {o.count} {o.name}: a count is 1 to {MAX_COUNT}")
    for r in reading.relations:
        if r.distance_cm is not None and r.distance_cm < 0:
            raise BadInput(f"{where}: '{_said(r)}': a distance must not be negative "
                           f"({r.distance_cm:g} cm)")
    faults = unrelated(reading, catalog)
    if faults:
        raise BadInput(f"{where}: {faults[0][1]}")


def _said(r: ReadRelation) -> str:
    return f"{r.subject} {r.relation} {r.reference or 'the table'}"


def unrelated(reading: Reading, catalog: Catalog) -> list[tuple[ReadRelation, str]]:
    """The relations of ``reading`` that relate no objects of it, each with the reason: a
    subject, reference or partner it does not hold, a reference for ``center`` or none for
    another relation, a partner for anything but ``either side of``, or an object related
    to itself."""
    names = item_names(reading.objects, catalog)
    out = []
    for r in reading.relations:
        said = _said(r)
        missing = [(role, name) for role, name in (("subject", r.subject),
                                                   ("reference", r.reference),
                                                   ("partner", r.partner))
                   if name is not None and name not in names]
        if missing:
            role, name = missing[0]
            out.append((r, f"{said!r}: its {role} {name!r} is not one of the objects read "
                           f"({', '.join(names)})"))
        elif (r.relation == CENTER) != (r.reference is None):
            out.append((r, f"{said!r}: only 'center' takes no reference"))
        elif (r.relation == EITHER_SIDE) != (r.partner is not None):
            out.append((r, f"{said!r}: 'either side of' relates two objects to a third, "
                           "and only it takes a partner"))
        elif r.subject in (r.reference, r.partner) or (r.partner and r.partner == r.reference):
            out.append((r, f"{said!r}: an object related to itself"))
    return out


def to_request(reading: Reading, catalog: Catalog, calls: Sequence[CallRecord] = (),
               warnings: Sequence[str] = ()) -> Request:
    """The request the pipeline takes from ``reading`` (checked first, see
    :func:`check_reading`): items for every diner, definite relations and choices."""
    check_reading(reading, catalog)
    wanted = [Wanted(catalog.specs[o.name], o.count, o.source, o.words)
              for o in reading.objects]
    items, _ = number_items(wanted)
    notes = list(warnings)
    relations: list[Relation] = []
    choices: list[Choice] = []
    for r in reading.relations:
        gap = None if r.distance_cm is None else r.distance_cm / 100
        if r.relation == BESIDE:
            assert r.reference is not None
            choices.append(beside(r.subject, r.reference, r.words, "request", gap))
        elif r.relation == EITHER_SIDE:
            assert r.reference is not None and r.partner is not None
            choices.append(either_side(r.subject, r.partner, r.reference, r.words, "request",
                                       gap))
        else:
            relations.append(Relation(r.subject, r.relation, r.reference, r.words, "request",
                                      gap))
    return Request(reading.text, for_diners(items, reading.diners), reading.diners,
                   tuple(relations), reading.read_by, tuple(calls), tuple(notes),
                   tuple(choices), reading.guessed)


__all__ = ["ReadObject", "ReadRelation", "Reading", "check_reading", "item_names",
           "to_request", "unrelated"]
