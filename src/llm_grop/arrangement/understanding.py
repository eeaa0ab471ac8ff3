"""Understanding a request in people's own words: the catalog matcher first, then the LLM
for what the matcher cannot account for.

The matcher (:func:`llm_grop.world.request.read_request`) reads what it can and returns
the chunks it cannot ("a glass of something cold", "the usual"). A chunk is sent to the
LLM only if one of its words may stand for tableware: a word of a catalog name or synonym,
or one of ``prompts/dining_words.yaml``; any other chunk ("happiness") is refused at once
with :class:`~llm_grop.errors.UnknownObject` and suggestions.

For each chunk the LLM is asked which catalog objects, and how many, it asks for
(``prompts/items.txt``, seed stage ``llm.items``, path k for the k-th chunk). The answer
is constrained where the backend allows: a GBNF grammar over the catalog's names for the
embedded model, a JSON Schema for ``openai`` servers that support structured output. It
is read by :func:`read_items_answer`, which takes JSON or lines such as ``2 dinner fork``,
and checked against the catalog: a name outside it is a one-line error with suggestions.
A chunk the LLM reads as no object ("cereal" beside "a bowl") is ignored with a warning,
unless nothing else in the request names an object: then it is refused as unknown.
"""

from __future__ import annotations

import functools
import json
import re
from collections.abc import Callable
from importlib import resources
from typing import Any

import yaml

from llm_grop import seeds
from llm_grop.errors import UnknownObject
from llm_grop.llm.base import CallLog, SamplingParams
from llm_grop.world.catalog import Catalog, singular_forms
from llm_grop.world.request import (
    MAX_OBJECTS,
    Mention,
    Reading,
    Request,
    read_request,
)
from llm_grop.world.request_reader import normalized
from llm_grop.world.request_words import NUMBERS

#: Characters of an answer read: an answer naming every catalog object fits many times.
MAX_ANSWER_CHARS = 20_000

#: Most answer lines read, and most words of a line taken as an object's name.
_MAX_LINES = 64
_MAX_NAME_WORDS = 4

_WORD = re.compile(r"[^\W\d_]+")
_COUNT = "|".join(["[0-9]+", "an?", *NUMBERS])
_LINE = re.compile(r"^(?:[-*\u2022]\s*|[0-9]+[.)]\s+(?=\D))?"
                   rf"(?:({_COUNT})\s*(?:x|\u00d7)?\s+)?"
                   r"(.+?)(?:\s*(?:x|\u00d7)\s*([0-9]+))?[\s.,;:!]*$")
_NONE = frozenset({"none", "nothing", "no objects", "no object", "n/a", ""})


def _asset(name: str) -> str:
    return resources.files("llm_grop.arrangement").joinpath(f"prompts/{name}").read_text("utf-8")


@functools.cache
def dining_words() -> frozenset[str]:
    """The words of ``prompts/dining_words.yaml``."""
    data = yaml.safe_load(_asset("dining_words.yaml"))
    return frozenset(str(w).lower() for w in data["words"])


def _catalog_words(catalog: Catalog) -> frozenset[str]:
    return frozenset(w for alias in catalog.aliases() for w in alias.split())


def may_name_tableware(text: str, catalog: Catalog) -> bool:
    """Whether a word of ``text`` may stand for tableware (see the module docstring)."""
    known = dining_words() | _catalog_words(catalog)
    return any(form in known for word in _WORD.findall(normalized(text).lower())
               for form in singular_forms(word))


def items_prompt(request: str, chunk: str, catalog: Catalog) -> str:
    """The question about ``chunk`` of ``request``, listing the catalog's names."""
    return _asset("items.txt").format(request=" ".join(request.split()), chunk=chunk,
                                      objects=", ".join(catalog.names()))


def _gbnf_literal(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def items_grammar(catalog: Catalog) -> str:
    """GBNF: ``none``, or 1 to 8 lines ``N name`` over the catalog's names (N up to 30)."""
    names = " | ".join(_gbnf_literal(n) for n in catalog.names())
    return ('root ::= "none" | line ("\\n" line){0,7}\n'
            'line ::= count " " name\n'
            'count ::= [1-9] | [12] [0-9] | "30"\n'
            f"name ::= {names}\n")


def items_schema(catalog: Catalog) -> dict[str, Any]:
    """JSON Schema of a structured answer: ``{"objects": [{"name": .., "count": ..}]}``,
    names from the catalog; an empty list means none."""
    item = {"type": "object", "additionalProperties": False, "required": ["name", "count"],
            "properties": {"name": {"type": "string", "enum": catalog.names()},
                           "count": {"type": "integer", "minimum": 1,
                                     "maximum": MAX_OBJECTS}}}
    return {"type": "object", "additionalProperties": False, "required": ["objects"],
            "properties": {"objects": {"type": "array", "items": item}}}


def _json_entries(text: str) -> list[tuple[object, object]] | None:
    """``(name, count)`` pairs of a JSON answer, or ``None`` when ``text`` is not one."""
    body = text.strip().removeprefix("```json").removeprefix("```").removesuffix("```").strip()
    if body[:1] not in ("{", "["):
        return None
    try:
        data = json.loads(body)
    except (json.JSONDecodeError, RecursionError):
        return None
    if isinstance(data, dict):
        data = data.get("objects", [])
    if not isinstance(data, list):
        return []
    out: list[tuple[object, object]] = []
    for entry in data:
        if isinstance(entry, dict):
            out.append((entry.get("name"), entry.get("count", 1)))
        elif isinstance(entry, str):
            out.append((entry, 1))
    return out


def _line_entries(text: str) -> list[tuple[object, object]]:
    """``(name, count)`` pairs of a line answer; prose lines come back as long names."""
    out: list[tuple[object, object]] = []
    for raw in text.splitlines()[:_MAX_LINES]:
        line = " ".join(normalized(raw).lower().split())[:200]
        m = _LINE.match(line)
        if not m or line in _NONE:
            continue
        word, name, after = m.group(1), m.group(2), m.group(3)
        count: object = 1
        if word is not None:
            count = int(word) if word.isdigit() else NUMBERS.get(word, 1)
        if after is not None:
            count = int(after)
        out.append((name, count))
    return out


def read_items_answer(text: str, catalog: Catalog) -> tuple[list[Mention], list[str]]:
    """The catalog objects an answer names, with counts, and the short names it gives that
    the catalog does not know. Takes JSON (``{"objects": [{"name", "count"}]}``, a list)
    or lines (``2 dinner fork``, ``- fork x2``, ``one knife``); "none" and prose lines
    name nothing. Only the first :data:`MAX_ANSWER_CHARS` characters are read."""
    text = text[:MAX_ANSWER_CHARS]
    entries = _json_entries(text)
    if entries is None:
        entries = _line_entries(text)
    mentions: list[Mention] = []
    unknown: list[str] = []
    for name, count in entries:
        if not isinstance(name, str) or isinstance(count, bool) or not isinstance(count, int):
            continue
        name = " ".join(name.lower().split()).strip(" .,:;!\"'")
        if name in _NONE:
            continue
        spec = catalog.lookup(name)
        if spec is None:
            if len(name.split()) <= _MAX_NAME_WORDS:
                unknown.append(name)
            continue
        if 1 <= count <= MAX_OBJECTS:
            mentions.append(Mention(spec, count))
    return mentions, unknown


def understand(text: str, catalog: Catalog, llm: CallLog | Callable[[], CallLog] | None,
               seed: int = 0, params: SamplingParams | None = None,
               say: Callable[[str], None] | None = None) -> Request:
    """The objects ``text`` asks for, with the relations it states: the matcher's reading,
    and the LLM's for each chunk the matcher cannot account for (``llm=None``: such a
    chunk is an :class:`~llm_grop.errors.UnknownObject`; a callable makes the LLM only
    when one is needed)."""
    reading = read_request(text, catalog)
    if not reading.unread:
        return reading.request()
    for chunk in reading.unread:
        if llm is None or not may_name_tableware(chunk.text, catalog):
            raise chunk.error()
    log = llm if isinstance(llm, CallLog) else llm()
    return _ask(reading, catalog, log, seed, params or SamplingParams(), say)


def _ask(reading: Reading, catalog: Catalog, llm: CallLog, seed: int,
         params: SamplingParams, say: Callable[[str], None] | None) -> Request:
    answers: list[list[Mention]] = []
    calls = []
    warnings = []
    for k, chunk in enumerate(reading.unread):
        if say is not None:
            say(f"asking {llm.model} what {chunk.text!r} asks for")
        record = llm.complete(items_prompt(reading.rest, chunk.text, catalog),
                              params.with_seed(seeds.int_seed(seed, "llm.items", k)),
                              items_grammar(catalog), schema=items_schema(catalog))
        calls.append(record)
        mentions, unknown = read_items_answer(record.response, catalog)
        if unknown:
            raise UnknownObject(unknown[0], catalog.suggest(unknown[0]),
                                f"request: the {llm.backend} LLM read {chunk.text!r} as")
        answers.append(mentions)
        if mentions:
            read = ", ".join(f"{m.count} {m.spec.name}" for m in mentions)
            warnings.append(f"the LLM read {chunk.text!r} as: {read}")
        else:
            warnings.append(f"the LLM read no object in {chunk.text!r}; ignored it")
    if not any(isinstance(p, Mention) for p in reading.parts) and not any(answers):
        raise reading.unread[0].error()
    return reading.request(answers, "llm", calls, warnings)


__all__ = ["dining_words", "items_grammar", "items_prompt", "items_schema",
                          "may_name_tableware", "read_items_answer", "understand"]
