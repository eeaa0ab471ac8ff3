"""How each front door names the settings record's fields: the command line's flags
(``m`` -> ``--configurations``), a sweep file's keys, the JSON fields and Python's keywords,
read from the fields' own metadata, and messages worded for each door."""

from __future__ import annotations

import re
from typing import Any

from llm_grop.errors import LLMGropError
from llm_grop.settings.record import Door, Interface, RunSettings, _extra


def extra(name: str) -> dict[str, Any]:
    """The metadata written beside field ``name`` (group, identity, door)."""
    return _extra(name)


def door(name: str) -> Door:
    """How the front doors spell field ``name``."""
    return Door(**extra(name).get("door", {}))


def help_text(name: str) -> str:
    """Field ``name``'s help, units included."""
    return RunSettings.model_fields[name].description or ""


def fields(group: str | None = None) -> list[str]:
    """The record's field names (of one ``group``), in their order."""
    return [n for n in RunSettings.model_fields if group is None or extra(n)["group"] == group]


def flag(name: str) -> str:
    """The command-line flag of field or parameter ``name``: ``m`` -> ``--configurations``,
    ``guess`` -> ``--no-guess``, anything else ``--name-with-dashes``."""
    if name in RunSettings.model_fields:
        d = door(name)
        if d.negate:
            return d.negate
        if d.cli:
            return d.cli
    return "--" + name.replace("_", "-")


def label(name: str, where: Interface, value: object = None) -> str:
    """Field or parameter ``name`` (with the ``value`` given for it, when it helps) in the
    words of the front door ``where``: ``--configurations 0``, ``m`` (a sweep file's
    key), ``"m"`` (a JSON field) or ``m=0`` (Python)."""
    field, dot, key = name.partition(".")
    if dot and field in RunSettings.model_fields and where == "cli":
        # An entry of a mapping setting: ``--sim-option timestep_s=x``.
        return f"{flag(field)} {key}" + ("" if value is None else f"={value}")
    known = name in RunSettings.model_fields
    d = door(name) if known else Door()
    if where == "cli":
        named = flag(name)
        if value is None or (known and d.negate):
            return named
        text = str(value)
        return f"{named} {text if text and ' ' not in text else repr(text)}"
    if where == "sweep":
        return d.sweep or name if value is None else f"{d.sweep or name} {value}"
    if where == "json":
        return d.json or name
    if where == "web":
        return d.web or f'"{d.json or name}"'
    if value is None:
        return name
    return f"{name}={value if isinstance(value, int | float) else str(value)!r}"


#: A setting a message mentions, spelled as Python's keyword: ``guess=False``, ``chairs=N``.
_MENTION = re.compile(r"\b([a-z][a-z_]*)=([^\s,;:)]+)")
#: Python's literals a mention may hold, as JSON spells them.
_JSON_LITERALS = {"True": "true", "False": "false", "None": "null"}


def words(text: str, where: Interface, names: tuple[str, ...] | None = None) -> str:
    """``text`` (a message or a warning of the API) with each setting it mentions as
    Python's keyword (``guess=False``) spelled as ``where`` spells it: ``--no-guess``,
    ``--chairs N``; only ``names`` when given (what an error says it mentions), else any
    field of the record."""
    if where == "python":
        return text

    def one(m: re.Match[str]) -> str:
        name, value = m.group(1), m.group(2)
        if name not in RunSettings.model_fields or names is not None and name not in names:
            return m.group(0)
        if where == "json":
            return f'"{label(name, where)}": {_JSON_LITERALS.get(value, value)}'
        if where == "web":
            return label(name, where) if door(name).web else \
                f'"{label(name, "json")}": {_JSON_LITERALS.get(value, value)}'
        if where == "sweep":
            return f"{label(name, where)}: {value}"
        return label(name, where, value)

    return _MENTION.sub(one, text)


def in_words(exc: LLMGropError, where: Interface) -> str:
    """``exc``'s one-line message with its parameter, and the settings it mentions
    (``exc.mentions``), named as the front door ``where`` names them."""
    detail = words(exc.detail if exc.param is not None else str(exc), where, exc.mentions)
    if exc.param is None:
        return detail
    shown = exc.value if where != "json" else None
    return f"{label(exc.param, where, shown)}: {detail}"


