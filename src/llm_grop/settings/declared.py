"""A plugin's own options: the frozen dataclass a simulator, an LLM backend or a method
declares as ``Options``, and a user's values checked against it.

The front doors carry these values as ``KEY=VALUE`` pairs (``--sim-option``,
``--llm-option``, ``--method-option``), mappings in a sweep file or JSON objects; the
settings record keeps them as sorted pairs (``sim_options``, ``backend_options``,
``method_options``), and the registry that builds the plugin checks them here, so an
unknown key or a value of the wrong type is one :class:`~llm_grop.errors.BadInput` naming
``FIELD.KEY``.
"""

from __future__ import annotations

import os
import typing
from collections.abc import Mapping
from dataclasses import MISSING, dataclass, fields
from pathlib import PurePath
from typing import Any

from pydantic import TypeAdapter, ValidationError

from llm_grop.errors import BadInput
from llm_grop.settings.reasons import first_reason


@dataclass(frozen=True)
class NoOptions:
    """The options of a plugin that declares none."""


def option_names(options: type) -> tuple[str, ...]:
    """The option names the dataclass ``options`` declares."""
    return tuple(f.name for f in fields(options))


def option_defaults(options: type) -> str:
    """The options of ``options`` with their defaults, as ``KEY=VALUE`` texts would set
    them (``context_tokens=2048, ...``; ``-`` for none)."""
    made = [f"{f.name}={_shown(f.default)}" if f.default is not MISSING else f.name
            for f in fields(options)]
    return ", ".join(made) or "-"


def _shown(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return str(value).lower()
    return str(value)


def path_options(options: type) -> tuple[str, ...]:
    """The options of ``options`` whose values name files (typed with a path, or marked
    ``metadata={"path": "file"}`` or ``"dir"``), which a network front door refuses: a
    client may not choose where the server reads or writes."""
    hints = typing.get_type_hints(options)
    return tuple(f.name for f in fields(options)
                 if f.metadata.get("path") or _names_path(hints.get(f.name)))


def _names_path(hint: Any) -> bool:
    if isinstance(hint, type) and issubclass(hint, PurePath | os.PathLike):
        return True
    return any(_names_path(arg) for arg in typing.get_args(hint))


def declared_options(options: type, given: Mapping[str, Any], *, owner: str,
                     param: str) -> Any:
    """``given`` (a user's values by option name) as an instance of the declared dataclass
    ``options``, each value checked against its type by pydantic. ``owner`` names the
    plugin in messages (``simulator 'mujoco'``), ``param`` the setting that carried the
    values (``sim_options``): the first problem is one :class:`BadInput` naming
    ``param.KEY``."""
    names = option_names(options)
    unknown = [k for k in given if k not in names]
    if unknown:
        have = f"its options: {', '.join(names)}" if names else "it declares none"
        raise BadInput(f"{owner} has no option {unknown[0]!r} ({have})",
                       param=f"{param}.{unknown[0]}")
    # A dataclass carries its own pydantic configuration, if any (``__pydantic_config__``).
    adapter = TypeAdapter(options)
    try:
        return adapter.validate_python(dict(given))
    except ValidationError as exc:
        error = exc.errors(include_url=False)[0]
        key = ".".join(str(k) for k in error.get("loc", ()))
        raise BadInput(first_reason(error), param=f"{param}.{key}",
                       value=error.get("input")) from None
