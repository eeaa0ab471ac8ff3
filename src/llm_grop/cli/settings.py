"""The command line's view of :class:`~llm_grop.settings.RunSettings`: its flags are made
from the record's fields (name, default, bounds, help), and the values they parse make a
record again, so no flag can drift from the field it sets."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from types import UnionType
from typing import Any, Literal, Union, get_args, get_origin

import click
from annotated_types import Ge, Gt, Le, Lt

from llm_grop.cli.options import F
from llm_grop.settings import RunSettings, door, fields, flag, help_text


def _parse_table(ctx: click.Context, param: click.Parameter, text: str | None) -> str | None:
    """``--table``'s text checked as the flags are read, in its one canonical spelling."""
    from llm_grop.world.table import Table

    return None if text is None else Table.parse(text).text


def _bounds(name: str) -> dict[str, Any]:
    """Field ``name``'s bounds as click's range arguments."""
    out: dict[str, Any] = {}
    for item in RunSettings.model_fields[name].metadata:
        if isinstance(item, Ge):
            out["min"] = item.ge
        elif isinstance(item, Gt):
            out["min"], out["min_open"] = item.gt, True
        elif isinstance(item, Le):
            out["max"] = item.le
        elif isinstance(item, Lt):
            out["max"], out["max_open"] = item.lt, True
    return out


def _base(annotation: Any) -> Any:
    """``annotation`` without ``| None``, and a tuple's element type."""
    if get_origin(annotation) in (Union, UnionType):
        annotation = next(a for a in get_args(annotation) if a is not type(None))
    if get_origin(annotation) is tuple:
        return get_args(annotation)[0]
    return annotation


def option(name: str, help: str | None = None) -> Callable[[F], F]:
    """The flag that sets field ``name`` (``help`` replaces the record's words where a
    command means something more particular, such as bench's seed of trial 0)."""
    info = RunSettings.model_fields[name]
    d = door(name)
    words = help or d.cli_help or help_text(name)
    kinds: dict[str, Any] = {"help": words}
    if d.metavar:
        kinds["metavar"] = d.metavar
    annotation = info.annotation
    base = _base(annotation)
    if d.negate:
        return click.option(d.negate, name, flag_value=not info.default,
                            default=info.default, help=words)
    if base is bool:
        return click.option(flag(name), name, is_flag=True, default=info.default, help=words)
    decls = [flag(name), *([d.short] if d.short else []), name]
    if get_origin(annotation) is tuple:
        kinds["multiple"] = True
    elif info.default is not None:
        kinds |= {"default": info.default, "show_default": True}
    if d.path is not None:
        kinds["type"] = click.Path(dir_okay=d.path == "dir", file_okay=d.path == "file",
                                   path_type=Path)
    elif get_origin(base) is Literal:
        kinds["type"] = click.Choice(get_args(base))
    elif base is int:
        kinds["type"] = click.IntRange(**_bounds(name))
    elif base is float:
        kinds["type"] = click.FloatRange(**_bounds(name))
    if name == "table":
        kinds["callback"] = _parse_table
    return click.option(*decls, **kinds)


def flags(*names: str, help: Mapping[str, str] | None = None) -> Callable[[F], F]:
    """Add the flags of fields ``names``, in that order in ``--help``."""
    made = [option(n, (help or {}).get(n)) for n in names]

    def add(f: F) -> F:
        for one in reversed(made):
            f = one(f)
        return f

    return add


def from_flags(params: Mapping[str, Any], **fixed: Any) -> RunSettings:
    """The record the parsed flags ``params`` describe (entries that are no field are
    left out), with ``fixed`` values on top; a bad value is :class:`BadInput` naming its
    flag."""
    values = {k: v for k, v in params.items() if k in RunSettings.model_fields}
    return RunSettings.make(values | fixed)


def checked_settings(params: Mapping[str, Any], **fixed: Any) -> RunSettings:
    """:func:`from_flags`, and what the record names that can be checked cheaply checked
    before any work: the LLM backend and its replay file, the preferences file."""
    from llm_grop.assembly import arrange_options, check_backend

    settings = from_flags(params, **fixed)
    check_backend(settings)
    arrange_options(settings)
    return settings


# Each command takes groups of the record's fields (its metadata's ``group``), so a field
# added to a group appears on every command that takes it.
#: The fields every command that calls an LLM takes, in ``--help``'s order.
LLM_FIELDS = ("llm", *fields("backend"))
#: The arrangement's fields, after the LLM's.
ARRANGE_FIELDS = tuple(f for f in fields("llm") if f != "llm")
#: Where the run happens and how it is planned and executed.
ROOM_FIELDS = ("table", "diners", *fields("sim"), *fields("plan"))
#: The executive's attempt counts.
ATTEMPT_FIELDS = fields("execution")
