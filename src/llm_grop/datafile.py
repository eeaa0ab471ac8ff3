"""Reading data files users may write (catalogs, tasks, scenes, sweeps, the contract's
JSON); errors name the file and the field and say what is wrong in the project's words
(``s.yaml: trials: expected a whole number, got 'two'``, ``s.yaml: trails: unknown key;
did you mean 'trials'?``), never pydantic's."""

from __future__ import annotations

import difflib
from collections.abc import Sequence
from types import UnionType
from typing import Annotated, Any, TypeVar, Union, get_args, get_origin

import yaml
from pydantic import BaseModel, RootModel, ValidationError

from llm_grop.errors import BadInput

M = TypeVar("M", bound=BaseModel)


def load_yaml_model(text: str, where: str, model: type[M], top_key: str, label_key: str,
                    error: type[BadInput] = BadInput) -> M:
    """``text`` parsed as YAML and validated as ``model``.

    Errors are ``error`` with one line: ``<where>[ line N]: <field path>: <reason>``;
    list entries in the path are labelled with their ``label_key`` value. ``top_key`` is
    the list a file of the wrong shape is told to hold ("" for none in particular).
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
        wanted = f" with a {top_key!r} list" if top_key else ""
        raise error(f"{where}: top level: expected a mapping{wanted}")
    return validated(model, raw, where, label_key, error)


def validated(model: type[M], raw: Any, where: str, label_key: str,
              error: type[BadInput] = BadInput) -> M:
    """``raw`` (parsed YAML or JSON) validated as ``model``; the first problem is ``error``
    with one line ``<where>: <field path>: <reason>``, in plain words (see
    :func:`first_problem`)."""
    try:
        return model.model_validate(raw)
    except ValidationError as exc:
        path, reason = first_problem(exc.errors(include_url=False), raw, label_key, model)
        raise error(f"{where}: {path}: {reason}") from None


def first_problem(errors: Sequence[Any], raw: Any, label_key: str,
                  model: Any = None) -> tuple[str, str]:
    """The first of pydantic's ``errors`` about ``raw`` as ``(field path, reason)`` in the
    project's words: no pydantic names (a union's member tags such as ``constrained-str``
    are left out of the path, and its members' complaints become one ``expected text or a
    list``); an unknown key gets a did-you-mean from ``model``'s keys at that place."""
    if not errors:
        return "top level", "not valid"
    err = errors[0]
    tag = _first_tag(raw, err)
    if tag is not None:
        # Every member of the union complained; the one that got furthest into the value,
        # or else one whose type matched, says what is wrong; else none matched at all.
        members = [e for e in errors if tuple(e["loc"][:tag]) == tuple(err["loc"][:tag])
                   and _first_tag(raw, e) == tag]
        err = max(members, key=lambda e: (len(_plain_loc(raw, e)), e["type"] not in _EXPECTED))
        if len(_plain_loc(raw, err)) == tag and all(e["type"] in _EXPECTED for e in members):
            wanted = list(dict.fromkeys(_EXPECTED[e["type"]] for e in members))
            reason = "expected " + ", ".join(wanted[:-1]) + (" or " if wanted[1:] else "") \
                + wanted[-1]
            return field_path(raw, _plain_loc(raw, err), label_key), _got(reason, err)
    loc = _plain_loc(raw, err)
    return field_path(raw, loc, label_key), _reason(err, _keys_at(model, loc[:-1]))


def problem_line(errors: Sequence[Any], raw: Any, model: Any = None, *,
                 label_key: str = "name", where: str | None = "body") -> str:
    """The first of a web request's validation ``errors`` as one line ``field: reason``,
    in the words of :func:`first_problem`; ``raw`` is the parsed body, and a location
    inside it starts with ``where`` (FastAPI's ``body``; ``None``: the locations are the
    body's own), which the line leaves out."""
    inside = list(errors) if where is None else [
        dict(e, loc=tuple(e.get("loc", ()))[1:]) for e in errors
        if tuple(e.get("loc", ()))[:1] == (where,)]
    if not inside or not isinstance(raw, dict):
        if not errors:
            return "request body: not valid"
        first = errors[0]
        named = ".".join(str(k) for k in first.get("loc", ()) if k != where)
        return f"{named or 'request body'}: {_reason(dict(first, loc=()))}"
    path, reason = first_problem(inside, raw, label_key, model)
    return f"{'request body' if path == 'top level' else path}: {reason}"


#: What a type error expected, in plain words.
_EXPECTED = {
    "string_type": "text", "int_type": "a whole number", "int_parsing": "a whole number",
    "int_from_float": "a whole number", "float_type": "a number", "float_parsing": "a number",
    "bool_type": "true or false", "bool_parsing": "true or false", "list_type": "a list",
    "tuple_type": "a list", "set_type": "a list", "dict_type": "an object",
    "model_type": "an object", "model_attributes_type": "an object",
    "none_required": "null", "finite_number": "a finite number"}

#: Plain words for the other errors; ``{...}`` are pydantic's context values.
_WORDS = {
    "greater_than": "must be greater than {gt}", "greater_than_equal": "must be at least {ge}",
    "less_than": "must be less than {lt}", "less_than_equal": "must be at most {le}",
    "multiple_of": "must be a multiple of {multiple_of}",
    "string_too_long": "must be at most {max_length} characters",
    "too_long": "must have at most {max_length} entries",
    "literal_error": "must be {expected}", "enum": "must be {expected}",
    "string_pattern_mismatch": "must match {pattern}"}


def _reason(err: Any, keys: Sequence[str] = ()) -> str:
    """A validation error's message in plain words, with the value it got; ``keys`` are
    the keys allowed where an unknown key was found (for a did-you-mean)."""
    kind, ctx = err["type"], err.get("ctx") or {}
    if kind == "missing":
        return "required, but missing"
    if kind == "extra_forbidden":
        return unknown_key(str(err["loc"][-1]) if err["loc"] else "", keys)
    if kind in _EXPECTED:
        msg = f"expected {_EXPECTED[kind]}"
    elif kind in ("string_too_short", "too_short"):
        n = ctx.get("min_length", 1)
        msg = "must not be empty" if n == 1 else \
            f"must have at least {n} {'characters' if kind == 'string_too_short' else 'entries'}"
    elif kind in _WORDS:
        try:
            msg = _WORDS[kind].format(**{k: f"{v:g}" if isinstance(v, float) else v
                                         for k, v in ctx.items()})
        except (KeyError, IndexError):
            msg = str(err["msg"])
    else:
        msg = str(err["msg"])
    for prefix, plain in (("Value error, ", ""), ("Assertion failed, ", ""),
                          ("Input should be ", "must be ")):
        if msg.startswith(prefix):
            msg = plain + msg.removeprefix(prefix)
    return _got(msg, err)


def _got(msg: str, err: Any) -> str:
    """``msg`` with the value the error got, when it is short and not a list or mapping."""
    value = err.get("input")
    if err["type"] == "missing" or isinstance(value, dict | list):
        return msg
    try:
        shown = repr(value)
    except ValueError:  # an integer too long for Python to write out
        return msg
    return msg + f", got {shown}" if len(shown) <= 40 else msg


def unknown_key(key: str, keys: Sequence[str]) -> str:
    """Why ``key`` is refused where ``keys`` are allowed: ``unknown key; did you mean 'x'?``
    for the closest allowed key, else ``unknown key; expected one of a, b`` (no list when
    ``keys`` is empty)."""
    close = difflib.get_close_matches(key, keys, n=1, cutoff=0.6)
    if close:
        return f"unknown key; did you mean {close[0]!r}?"
    return "unknown key" + (f"; expected one of {', '.join(keys)}" if keys else "")


def _first_tag(raw: Any, err: Any) -> int | None:
    """Where in ``err``'s location pydantic named a union's member (``constrained-str``,
    ``list[int]``, a model's name) rather than a key of the value: a text step into a value
    that is no mapping, or to a key the mapping lacks (other than a missing one)."""
    node, loc = raw, err["loc"]
    for k, key in enumerate(loc):
        if isinstance(node, dict) and key in node:
            node = node[key]
        elif isinstance(key, str):
            return None if err["type"] == "missing" and k == len(loc) - 1 else k
        else:
            node = _item(node, key)
    return None


def _item(node: Any, index: int) -> Any:
    """Entry ``index`` of the list ``node``; a value that is no list was read as a list of
    one, so its entry 0 is the value itself."""
    if isinstance(node, list):
        return node[index] if 0 <= index < len(node) else None
    return node if index == 0 else None


def _plain_loc(raw: Any, err: Any) -> tuple[int | str, ...]:
    """``err``'s location without the union members' tags: keys and indices only."""
    loc = tuple(err["loc"])
    while (tag := _first_tag(raw, {**err, "loc": loc})) is not None:
        loc = loc[:tag] + loc[tag + 1:]
    return loc


def _keys_at(model: Any, loc: Sequence[int | str]) -> list[str]:
    """The keys a model allows at ``loc`` inside ``model`` (a pydantic model class), in
    the model's order; empty where that is not a model."""
    if model is None:
        return []
    types = _leaves([model])
    for key in loc:
        inner: list[Any] = []
        for t in types:
            args = get_args(t)
            if _is_model(t):
                field = t.model_fields.get(key) if isinstance(key, str) else None
                inner += [field.annotation] if field is not None else []
            elif isinstance(key, int) and get_origin(t) in (list, tuple, set, frozenset) \
                    and args:
                inner.append(args[0])
            elif get_origin(t) is dict and len(args) == 2:
                inner.append(args[1])
        types = _leaves(inner)
    keys = [f.alias or name for t in types if _is_model(t) for name, f in t.model_fields.items()]
    return list(dict.fromkeys(keys))


def _is_model(t: Any) -> bool:
    return isinstance(t, type) and issubclass(t, BaseModel)


def _leaves(types: Sequence[Any]) -> list[Any]:
    """``types`` with unions, ``Annotated`` and root models opened up to what they hold."""
    out: list[Any] = []
    for t in types:
        if get_origin(t) is Annotated:
            out += _leaves([get_args(t)[0]])
        elif get_origin(t) in (Union, UnionType):
            out += _leaves(get_args(t))
        elif _is_model(t) and issubclass(t, RootModel):
            out += _leaves([t.model_fields["root"].annotation])
        else:
            out.append(t)
    return out


def field_path(raw: Any, loc: tuple[int | str, ...], label_key: str) -> str:
    """A readable path such as ``objects[2] ('mug').size`` for a validation error."""
    parts: list[str] = []
    node = raw
    for key in loc:
        if isinstance(key, int) and not (isinstance(node, dict) and key in node):
            if node is not None and not isinstance(node, list) and key == 0:
                # One value read as a list of one: the file has no list to index.
                continue
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
