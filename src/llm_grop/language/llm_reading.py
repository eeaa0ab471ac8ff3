"""The LLM's reading of a whole request: its prompt, its grammar and JSON Schema, and the
reader of its answer.

The prompt (``prompts/reading.txt``) lists the catalog's names and the reading's relations
and asks for lines such as ``object: 2 dinner fork | "two forks"`` and ``relation: dinner
fork | to the left of | dinner plate | 2 cm | "the fork 2 cm left of the plate"``. The
answer is constrained where the backend allows: a GBNF grammar over the catalog's names
for llama.cpp (the embedded model), a JSON Schema for ``openai`` servers with structured
output (``{"diners", "objects", "relations"}``); a server that turns schemas down answers
in the lines, which :func:`read_reading_answer` reads as well as the JSON.
"""

from __future__ import annotations

import functools
import json
import re
from collections.abc import Mapping
from dataclasses import replace
from importlib import resources
from typing import Any

from llm_grop.errors import BadInput, UnknownObject
from llm_grop.language.distance import DASHES, parse_distance_cm
from llm_grop.language.reading import (
    Reading,
    ReadObject,
    ReadRelation,
    check_reading,
    unrelated,
)
from llm_grop.language.vocabulary import EITHER_SIDE, READING_RELATIONS, phrase_table
from llm_grop.language.words import normalized
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import CENTER
from llm_grop.world.request import MAX_COUNT, MAX_DINERS

#: Characters of an answer read: an answer naming every catalog object fits many times.
MAX_ANSWER_CHARS = 20_000
#: Most answer lines read.
_MAX_LINES = 64
#: Most characters of a quoted ``words`` field kept.
_MAX_WORDS_CHARS = 300

_NUMBERING = re.compile(r"^\s*(?:[-*\u2022>]+|\(?[0-9]+[.)])\s*")
_QUOTED = re.compile(r'^["\u201c\u2018\'](.*)["\u201d\u2019\']$')
_DISTANCE = re.compile(r"^-?\s*[0-9]+(?:\.[0-9]+)?\s*[a-z]*$")
_INSTANCE = re.compile(r"^(.*?)\s+([0-9]+)$")
_NO_REFERENCE = frozenset({"", "table", "the table", "none", "null", "-"})


class NothingRead(BadInput):
    """The LLM's answer names no object."""


@functools.cache
def _template() -> str:
    return resources.files("llm_grop.language").joinpath("prompts/reading.txt").read_text(
        "utf-8")


def reading_prompt(request: str, catalog: Catalog) -> str:
    """The question that reads ``request`` whole, listing the catalog's names."""
    return _template().format(request=" ".join(request.split()),
                              objects=", ".join(catalog.names()),
                              relations=", ".join(READING_RELATIONS)).strip()


def _literal(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def reading_grammar(catalog: Catalog) -> str:
    """GBNF for a line answer: the diners, 1 to 8 objects over the catalog's names, and up
    to 6 relations between item names."""
    names = " | ".join(_literal(n) for n in catalog.names())
    rels = " | ".join(_literal(r) for r in READING_RELATIONS if r not in (CENTER, EITHER_SIDE))
    return ('root ::= "diners: " count "\\n" object ("\\n" object){0,7} ("\\n" relation){0,5}\n'
            'object ::= "object: " count " " name\n'
            'relation ::= "relation: " item " | " ( rel " | " item distance? | "center" | '
            '"either side of | " item " | with " item )\n'
            'distance ::= " | " [1-9] [0-9]? " cm"\n'
            'item ::= name (" " [2-9])?\n'
            'count ::= [1-9] | "1" [0-2]\n'
            f"name ::= {names}\n"
            f"rel ::= {rels}\n")


def reading_schema(catalog: Catalog) -> dict[str, Any]:
    """JSON Schema of a structured answer (strict: every field required, none extra)."""
    obj = {"type": "object", "additionalProperties": False,
           "required": ["name", "count", "words"],
           "properties": {"name": {"type": "string", "enum": catalog.names()},
                          "count": {"type": "integer", "minimum": 1, "maximum": MAX_COUNT},
                          "words": {"type": "string"}}}
    rel = {"type": "object", "additionalProperties": False,
           "required": ["subject", "relation", "reference", "distance_cm", "partner", "words"],
           "properties": {"subject": {"type": "string"},
                          "relation": {"type": "string", "enum": list(READING_RELATIONS)},
                          "reference": {"type": ["string", "null"]},
                          "distance_cm": {"type": ["number", "null"]},
                          "partner": {"type": ["string", "null"]},
                          "words": {"type": "string"}}}
    return {"type": "object", "additionalProperties": False,
            "required": ["diners", "objects", "relations"],
            "properties": {"diners": {"type": "integer", "minimum": 1, "maximum": MAX_DINERS},
                           "objects": {"type": "array", "items": obj},
                           "relations": {"type": "array", "items": rel}}}


def answer_of(reading: Reading) -> str:
    """``reading`` as a JSON answer that :func:`read_reading_answer` reads back to it (what
    a model that reads well returns)."""
    return json.dumps({
        "diners": reading.diners,
        "objects": [{"name": o.name, "count": o.count, "words": o.words}
                    for o in reading.objects],
        "relations": [{"subject": r.subject, "relation": r.relation, "reference": r.reference,
                       "distance_cm": r.distance_cm, "partner": r.partner, "words": r.words}
                      for r in reading.relations]})


def _json_answer(text: str) -> dict[str, Any] | None:
    """The answer's JSON object, or ``None`` when it is no JSON."""
    body = text.strip().removeprefix("```json").removeprefix("```").removesuffix("```").strip()
    if body[:1] not in ("{", "["):
        return None
    try:
        data = json.loads(body)
    except (json.JSONDecodeError, RecursionError):
        return None
    if isinstance(data, list):
        return {"objects": data}
    return data if isinstance(data, dict) else None


def _fields(rest: str) -> tuple[list[str], str]:
    """The ``|``-separated fields of a line, and its quoted words (the last field if
    quoted)."""
    fields = [f.strip() for f in rest.split("|")]
    words = ""
    if fields and _QUOTED.match(fields[-1]):
        words = _QUOTED.match(fields.pop())[1]  # type: ignore[index]
    return fields, words


def _line_answer(text: str) -> dict[str, Any]:
    """The diners, objects and relations of a line answer; other lines are prose."""
    out: dict[str, Any] = {"objects": [], "relations": []}
    for raw in text.splitlines()[:_MAX_LINES]:
        line = _NUMBERING.sub("", normalized(raw)).strip()
        key, sep, rest = line.partition(":")
        key = key.strip().lower().strip("*_ ")
        if not sep:
            continue
        if key in ("diners", "diner", "people"):
            m = re.match(r"\s*([0-9]+)", rest)
            out["diners"] = int(m.group(1)) if m else rest.strip()
        elif key in ("object", "objects"):
            fields, words = _fields(rest)
            m = re.match(r"^([0-9]+)\s*(?:x|\u00d7)?\s+(.+)$", fields[0]) if fields else None
            name, count = (m.group(2), int(m.group(1))) if m else (fields[0] if fields else "", 1)
            out["objects"].append({"name": name, "count": count, "words": words})
        elif key in ("relation", "relations"):
            fields, words = _fields(rest)
            entry: dict[str, Any] = {"subject": fields[0] if fields else "",
                                     "relation": fields[1] if len(fields) > 1 else "",
                                     "reference": None, "distance_cm": None, "partner": None,
                                     "words": words}
            for f in fields[2:]:
                low = f.lower()
                if low.startswith("with "):
                    entry["partner"] = f[5:].strip()
                elif _DISTANCE.match(low.replace(" ", "")) or _DISTANCE.match(low):
                    entry["distance_cm"] = f
                elif entry["reference"] is None:
                    entry["reference"] = f
            out["relations"].append(entry)
    return out


def _name(value: object, catalog: Catalog, where: str) -> str:
    """The catalog name (with an instance number: "dinner fork 2") ``value`` gives."""
    if not isinstance(value, str) or not value.strip():
        raise BadInput(f"{where}: an object without a name")
    text = " ".join(value.lower().split())[:100]
    m = _INSTANCE.match(text)
    k = int(m.group(2)) if m else 1
    spec = catalog.lookup(m.group(1) if m else text)
    if spec is None:
        raise UnknownObject(text, catalog.suggest(text), where)
    return spec.name if k == 1 else f"{spec.name} {k}"


def _relation(value: object, where: str) -> str:
    """The reading relation ``value`` names, also as any phrase of the vocabulary."""
    text = " ".join(str(value).lower().replace("-", " ").split())
    if text in READING_RELATIONS:
        return text
    words = text.split()
    m = phrase_table().match(words, 0) if words else None
    if m is None or m.end != len(words):
        raise BadInput(f"{where}: unknown relation {str(value)[:60]!r}; the relations are "
                       f"{', '.join(READING_RELATIONS)}")
    return m.relation


def _distance_cm(value: object, where: str) -> float | None:
    """A relation's ``distance_cm``: a number, or text such as "2 cm" or "1 inch"."""
    if value is None or value == "":
        return None
    if isinstance(value, bool):
        raise BadInput(f"{where}: distance {value!r} is no number")
    if isinstance(value, int | float):
        cm = float(value)
    else:
        text = str(value).strip()[:40]
        cm = parse_distance_cm(text.lstrip(DASHES).strip())
        if cm is None:
            raise BadInput(f"{where}: distance {text!r} is no distance")
        if text[:1] in DASHES:
            cm = -cm
    if cm != cm or cm in (float("inf"), float("-inf")):
        raise BadInput(f"{where}: distance {value!r} is no number")
    return cm


def _words(value: object) -> str:
    return " ".join(str(value).split())[:_MAX_WORDS_CHARS] if isinstance(value, str) else ""


def read_reading_answer(text: str, request: str, catalog: Catalog, where: str = "request"
                        ) -> tuple[Reading, list[str]]:
    """The reading an LLM's ``text`` gives of ``request`` (JSON or lines; only the first
    :data:`MAX_ANSWER_CHARS` characters are read), checked like any reading, and a warning
    for each relation left out because it names an unknown relation or relates no objects
    of the reading (see :func:`~llm_grop.language.reading.unrelated`): a weak model's
    stray lines never refuse the objects it read.

    Raises :class:`UnknownObject` (with suggestions) for a name outside the catalog and
    :class:`BadInput` for no object, a count or diners outside 1 to 12, or a negative
    distance; each message starts with ``where``.
    """
    text = text[:MAX_ANSWER_CHARS]
    data = _json_answer(text)
    if data is None:
        data = _line_answer(text)
    objects = []
    for entry in _entries(data.get("objects")):
        count = entry.get("count", 1)
        name = _name(entry.get("name"), catalog, where)
        if isinstance(count, bool) or not isinstance(count, int):
            raise BadInput(f"{where}: {name}: count {count!r} is no whole number")
        if not 1 <= count <= MAX_COUNT:
            raise BadInput(f"{where}: {count} {name}: a count is 1 to {MAX_COUNT}")
        objects.append(ReadObject(name.rsplit(" ", 1)[0] if _INSTANCE.match(name) else name,
                                  count, "request", _words(entry.get("words"))))
    relations = []
    notes: list[str] = []
    for entry in _entries(data.get("relations")):
        try:
            relation = _relation(entry.get("relation"), where)
        except BadInput as exc:
            notes.append(f"ignored a relation of the LLM's reading: {str(exc).split(': ', 2)[-1]}")
            continue
        ref = entry.get("reference")
        reference = None if ref is None or (isinstance(ref, str) and ref.strip().lower() in
                                            _NO_REFERENCE) else _name(ref, catalog, where)
        partner = entry.get("partner")
        relations.append(ReadRelation(
            _name(entry.get("subject"), catalog, where), relation,
            None if relation == CENTER else reference,
            _distance_cm(entry.get("distance_cm"), where),
            None if partner in (None, "") else _name(partner, catalog, where),
            _words(entry.get("words"))))
    diners = data.get("diners", 1)
    if isinstance(diners, bool) or not isinstance(diners, int):
        raise BadInput(f"{where}: diners {str(diners)[:40]!r} is no whole number")
    reading = Reading(" ".join(request.split()), tuple(objects), tuple(relations), diners,
                      "llm")
    if not objects:
        raise NothingRead(f"{where}: no object in {reading.text!r}")
    faults = unrelated(reading, catalog)
    if faults:
        dropped = {id(r) for r, _ in faults}
        said = list(dict.fromkeys(f"'{r.subject} {r.relation} {r.reference or 'the table'}'"
                                  for r, _ in faults))
        notes.append(f"ignored {len(faults)} relation(s) of the LLM's reading that relate "
                     f"none of its objects ({', '.join(names_of(reading))}): "
                     f"{', '.join(said[:3])}{', …' if len(said) > 3 else ''}")
        reading = replace(reading, relations=tuple(r for r in reading.relations
                                                   if id(r) not in dropped))
    check_reading(reading, catalog, where)
    return reading, notes


def names_of(reading: Reading) -> list[str]:
    """The reading's objects as "12 wine glass": short enough for one warning line."""
    return [f"{o.count} {o.name}" for o in reading.objects]


def _entries(value: object) -> list[Mapping[str, Any]]:
    """The dict entries of a list (strings are names); anything else holds none."""
    if not isinstance(value, list):
        return []
    return [e if isinstance(e, dict) else {"name": e} for e in value[:_MAX_LINES]
            if isinstance(e, dict | str)]


__all__ = ["MAX_ANSWER_CHARS", "NothingRead", "answer_of", "read_reading_answer", "reading_grammar",
           "reading_prompt", "reading_schema"]
