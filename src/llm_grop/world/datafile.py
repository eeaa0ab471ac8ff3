"""Reading data files users may write (catalogs, tasks, scenes, the contract's JSON); errors
name the field."""

from __future__ import annotations

from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ValidationError

from llm_grop.errors import BadInput

M = TypeVar("M", bound=BaseModel)


def load_yaml_model(text: str, where: str, model: type[M], top_key: str, label_key: str,
                    error: type[BadInput] = BadInput) -> M:
    """``text`` parsed as YAML and validated as ``model``.

    Errors are ``error`` with one line: ``<where>[ line N]: <field path>: <reason>``;
    list entries in the path are labelled with their ``label_key`` value.
    """
    try:
        raw = yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" line {mark.line + 1}" if mark is not None else ""
        raise error(f"{where}{at}: not valid YAML") from None
    except (ValueError, LookupError, AttributeError, TypeError, OverflowError, RecursionError):
        # PyYAML's constructors raise these for a tagged scalar they cannot convert
        # ("!!int 0x", "!!bool maybe", "!!timestamp x", "!!float"), and Python for nesting
        # deeper than its stack.
        raise error(f"{where}: not valid YAML (a value cannot be read)") from None
    if not isinstance(raw, dict):
        raise error(f"{where}: top level: expected a mapping with a {top_key!r} list")
    return validated(model, raw, where, label_key, error)


def validated(model: type[M], raw: Any, where: str, label_key: str,
              error: type[BadInput] = BadInput) -> M:
    """``raw`` (parsed YAML or JSON) validated as ``model``; the first problem is ``error``
    with one line ``<where>: <field path>: <reason>``."""
    try:
        return model.model_validate(raw)
    except ValidationError as exc:
        err = exc.errors()[0]
        raise error(f"{where}: {field_path(raw, err['loc'], label_key)}: {_reason(err)}"
                    ) from None


#: Plain words for pydantic's messages that name its own classes.
_PLAIN = {"model_type": "expected an object", "dict_type": "expected an object"}


def _reason(err: Any) -> str:
    """A validation error's message in plain words, with the value it got."""
    msg = _PLAIN.get(err["type"], str(err["msg"]).removeprefix("Value error, "))
    value = err.get("input")
    if err["type"] != "missing" and not isinstance(value, dict | list) \
            and len(repr(value)) <= 40:
        msg += f", got {value!r}"
    return msg


def field_path(raw: Any, loc: tuple[int | str, ...], label_key: str) -> str:
    """A readable path such as ``objects[2] ('mug').size`` for a validation error."""
    parts: list[str] = []
    node = raw
    for key in loc:
        if isinstance(key, int):
            label = f"[{key}]"
            if isinstance(node, list) and key < len(node):
                node = node[key]
                if isinstance(node, dict) and str(node.get(label_key, "")).strip() \
                        and not parts[1:]:
                    label += f" ({label_key} {node[label_key]!r})" if label_key == "id" \
                        else f" ({node[label_key]!r})"
            parts.append(label)
        else:
            # A key that is not plain text (a line break, a control character) is quoted,
            # so that the message stays on one line.
            text = str(key) if str(key).isprintable() else repr(key)
            parts.append(f".{text}" if parts else text)
            node = node.get(key) if isinstance(node, dict) else None
    return "".join(parts) or "top level"
