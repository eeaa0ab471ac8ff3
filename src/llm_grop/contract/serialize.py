"""The one place where arrangement records turn into the contract's JSON and back, through
the models of :mod:`llm_grop.contract.models`, and where an arrangement or run JSON file is
read."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any, TypeVar

from llm_grop.contract.models import (
    ArrangementDoc,
    Doc,
    FailureDoc,
    LLMCallDoc,
    LLMDoc,
    ObjectDoc,
    RelationDoc,
    RevisionDoc,
    TableDoc,
)
from llm_grop.datafile import validated
from llm_grop.errors import BadInput
from llm_grop.files.jsonio import rounded
from llm_grop.world.arrangement import Arrangement, Placement
from llm_grop.world.failure import Revision
from llm_grop.world.llmlog import CallRecord, LLMSummary
from llm_grop.world.relation import Relation
from llm_grop.world.seat import Seat
from llm_grop.world.table import Table

D = TypeVar("D", bound=Doc)


def read_doc(model: type[D], data: Any, where: str) -> D:
    """``data`` (parsed JSON) validated as ``model``.

    Raises :class:`BadInput` with one line ``<where>: <field path>: <reason>``; list
    entries in the path are labelled with their ``name`` (``objects[1] ('dinner fork').x``).
    """
    if not isinstance(data, Mapping):
        raise BadInput(f"{where}: expected a JSON object, got {type(data).__name__}")
    return validated(model, data, where, "name")


def _relation(rel: Relation, line: bool = False) -> RelationDoc:
    extra: dict[str, Any] = {"line": rel.line} if line else {}
    if rel.source == "request" and rel.line:
        extra["words"] = rel.line
    if rel.gap_m is not None:
        extra["gap_m"] = rounded(rel.gap_m)
    if rel.revision is not None:
        extra["revision"] = rel.revision
    if rel.learned_from:
        extra["examples"] = list(rel.learned_from)
    return RelationDoc(subject=rel.subject, relation=rel.relation, reference=rel.reference,
                       source=rel.source, **extra)


def _object(p: Placement, origin: tuple[str, str] | None = None, physical: bool = False
            ) -> ObjectDoc:
    extra: dict[str, Any] = {"diner": p.diner} if p.diner is not None else {}
    if origin is not None:
        extra["source"] = origin[0]
        if origin[1]:
            extra["words"] = origin[1]
    if physical:
        extra |= {"z_m": rounded(p.z_m), "tilt_rad": rounded(p.tilt_rad)}
    return ObjectDoc(name=p.name, x=rounded(p.x), y=rounded(p.y), yaw=rounded(p.yaw),
                     shape=p.shape, size=(rounded(p.size[0]), rounded(p.size[1])), on=p.on,
                     kind=p.kind or p.name, height=rounded(p.height), **extra)


def _call(c: CallRecord) -> LLMCallDoc:
    return LLMCallDoc(prompt=c.prompt, response=c.response, latency_s=round(c.latency_s, 4),
                      prompt_tokens=c.prompt_tokens, completion_tokens=c.completion_tokens,
                      seed=c.seed, **({"cached": True} if c.cached else {}))


def _revision(r: Revision) -> RevisionDoc:
    f = r.failure
    return RevisionDoc(
        round=r.round,
        failure=FailureDoc(kind=f.kind, reason=f.reason, objects=list(f.objects),
                           relations=[_relation(x, line=True) for x in f.relations]),
        asked=r.asked, **({"answer": r.answer} if r.answer else {}), outcome=r.outcome,
        **({"note": r.note} if r.note else {}),
        added=[_relation(x) for x in r.added], removed=[_relation(x) for x in r.removed])


def arrangement_doc(a: Arrangement, *, llm_log: bool = True, physical: bool = False
                    ) -> ArrangementDoc:
    """The contract's arrangement document of ``a``; ``llm_log=False`` leaves the LLM's
    call log out (its backend, model and call count stay); ``physical`` writes each
    object's ``z_m`` and ``tilt_rad`` (an executed arrangement, the run JSON's ``final``)."""
    llm: dict[str, Any] = {}
    origins = {name: (source, words) for name, source, words in a.origins}
    if a.llm is not None:
        log = {"log": [_call(c) for c in a.llm.calls]} if llm_log else {}
        chosen = {"chosen_by": a.llm.chosen_by} if a.llm.chosen_by is not None else {}
        llm["llm"] = LLMDoc(backend=a.llm.backend, model=a.llm.model, calls=len(a.llm.calls),
                            **chosen, **log)
    return ArrangementDoc(
        request=a.request,
        table=TableDoc(shape="circle" if a.table.is_round else "rectangle",
                       size=(rounded(a.table.width), rounded(a.table.depth)),
                       **({"diners": [tuple(rounded(v) for v in s.as_list())
                                      for s in a.table.diners]} if a.table.diners else {})),
        objects=[_object(p, origins.get(p.name), physical) for p in a.placements],
        relations=[_relation(r) for r in a.relations],
        **llm,
        warnings=list(a.warnings),
        conflicts=[[_relation(r, line=True) for r in core] for core in a.conflicts],
        **({"revisions": [_revision(r) for r in a.revisions]} if a.revisions else {}),
        **({"request_read_by": a.read_by} if a.read_by is not None else {}))


def arrangement_to_dict(a: Arrangement) -> dict[str, Any]:
    """The contract's arrangement JSON as a dict."""
    return arrangement_doc(a).to_json()


def arrangement_from_dict(data: Mapping[str, Any], where: str = "arrangement") -> Arrangement:
    """An :class:`Arrangement` from the contract's JSON (as written by any system).

    An object without ``shape`` is a box; one without ``size`` is bad input here (the
    rater fills both in from the catalog instead).
    """
    doc = read_doc(ArrangementDoc, data, where)
    placements = []
    for i, o in enumerate(doc.objects):
        if o.size is None:
            raise BadInput(f"{where}: objects[{i}] ({o.name!r}).size: missing")
        placements.append(Placement(o.name, o.x, o.y, o.yaw, o.shape or "box", o.size, o.on,
                                    o.kind or o.name, o.height or 0.0, o.diner,
                                    o.z_m or 0.0, o.tilt_rad or 0.0))
    try:
        relations = tuple(Relation(r.subject, r.relation, r.reference, r.words or "",
                                   source=r.source or "llm", gap_m=r.gap_m,
                                   revision=r.revision,
                                   learned_from=tuple(r.examples or ()))
                          for r in doc.relations)
    except ValueError as exc:
        raise BadInput(f"{where}: relations: {exc}") from None
    llm = LLMSummary(doc.llm.backend, doc.llm.model, chosen_by=doc.llm.chosen_by) \
        if doc.llm is not None else None
    origins = tuple((o.name, o.source, o.words or "") for o in doc.objects
                    if o.source is not None)
    return Arrangement(doc.request, table_of(doc, where), tuple(placements), relations, llm,
                       tuple(doc.warnings), read_by=doc.request_read_by, origins=origins)


def table_of(doc: ArrangementDoc, where: str = "arrangement") -> Table:
    """The document's table with its diners; :class:`BadInput` for a seat inside the top
    or an object whose ``diner`` has no seat."""
    seats = tuple(Seat(*d) for d in doc.table.diners or ())
    try:
        table = Table(*doc.table.size, doc.table.shape, seats)
    except BadInput as exc:
        raise BadInput(f"{where}: {exc}") from None
    for i, o in enumerate(doc.objects):
        if o.diner is not None and o.diner >= len(table.seats):
            raise BadInput(f"{where}: objects[{i}] ({o.name!r}).diner: {o.diner} but the "
                           f"table seats {len(table.seats)} diner(s)")
    return table


def read_arrangement_file(path: Path) -> tuple[dict[str, Any], str | None, str]:
    """``(arrangement, run request, where)`` from an arrangement or run JSON file: the
    arrangement as parsed JSON, not yet validated, and ``where`` naming it in messages.

    A run JSON (one with a ``final`` key) gives its ``final`` arrangement, with the
    run's ``request`` as the request when it has one.
    """
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise BadInput(f"{path}: cannot read ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise BadInput(f"{path}: not UTF-8 text") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise BadInput(f"{path}: not valid JSON (line {exc.lineno}: {exc.msg})") from None
    if not isinstance(data, dict):
        raise BadInput(f"{path}: expected a JSON object (an arrangement or a run JSON)")
    if "final" not in data:
        return data, None, str(path)
    # Only `final` and `request` of a run JSON are read (and `final` is validated by its
    # reader as an arrangement): a run written by another system may lack the rest.
    final = data["final"]
    if not isinstance(final, dict):
        raise BadInput(f"{path}: final: expected an arrangement object")
    request = data.get("request")
    if request is not None and not isinstance(request, str):
        raise BadInput(f"{path}: request: expected a string, got {request!r}")
    return final, request, f"{path}: final"
