"""Sweep files: a grid of bench experiments, each combination of its values one cell.

A sweep file is YAML in the bench's terms. Its top level gives what every cell shares;
``grid`` gives, for any of the same keys, a list of values, and the sweep runs every
combination of them::

    # chairs.yaml: 3 x 3 cells, each the paper's 640 episodes
    tasks: paper
    methods: tpra,latp,grop,llm-grop
    trials: 20
    images: false
    llm: {backend: replay, replay: ../benchmarks/data/embedded_calls.jsonl}
    grid:
      chairs: [0, 1, 4]
      table: [scene, 1.8x0.9m, round:1.2m]

Keys (:class:`Values`): ``tasks``, ``methods``, ``trials``, ``images``, ``llm``
(``backend``, ``model``, ``base_url``, ``replay``, ``temperature``, and a ``name`` for the
cell's directory), and every other setting of a run by its name in the settings record
(:class:`~llm_grop.settings.RunSettings`): ``seed``, ``scene``, ``chairs``, ``table``,
``simulator``, ``feasibility``, ``weight``, ``fidelity_weight``, ``m``, ``nav_attempts``,
``grasp``, ...; ``preferences`` is a preferences file and ``prefer`` a list of sentences.
A key left out takes the bench's default. Paths are relative to the sweep file. Each cell is
an experiment directory named after its grid values (``chairs=4,table=round_1.2m``),
resumable and refused if it holds another experiment's results, as ``llm-grop bench --out``
is.

One value stands for a list of one: ``tasks: 3`` is ``tasks: [3]``, and in ``grid``
``chairs: 4`` is ``chairs: [4]`` (a grid key of one value still names the cells). In
``grid``, ``tasks: [1, 2]`` is two cells, one per task; a cell of several tasks is a list
in the list (``tasks: [[1, 2], paper]``) or text (``tasks: ['1,2', paper]``). The other
top-level keys take one value: a list there is refused with a pointer to ``grid``.

A mistake is one line naming the file and the field in plain words: ``s.yaml: trials:
expected a whole number, got 'two'``, ``s.yaml: grid.chiars: unknown key; did you mean
'chairs'?``.
"""

from __future__ import annotations

import itertools
import json
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    ValidationInfo,
    create_model,
    field_validator,
)

from llm_grop.datafile import load_yaml_model
from llm_grop.errors import BadInput
from llm_grop.settings import RunSettings, door

#: Longest cell directory name, in characters (a file system allows 255 bytes).
MAX_NAME = 120
#: The file in a sweep's directory that marks it as one and lists its cells.
MARKER = "sweep.json"

_UNSAFE = re.compile(r"[^A-Za-z0-9._+=-]+")

Text = Annotated[str, Field(min_length=1, max_length=500)]


def _one_task(value: Any) -> Any:
    """``tasks: 3`` read as ``tasks: [3]``: one task id is a list of one."""
    return [value] if isinstance(value, int) and not isinstance(value, bool) else value


#: Tasks as the bench's ``--tasks`` text (``paper``, ``1-8``, ``1,3``), or a list of ids.
Tasks = Annotated[Text | list[Annotated[int, Field(ge=0)]], BeforeValidator(_one_task)]


#: Settings a sweep file does not set: each trial's own, and how answers are cached.
_NOT_SWEPT = ("task", "method", "cache")


def _setting_field(name: str) -> tuple[Any, Any]:
    """The settings record's field ``name`` as an optional key of a sweep file, checked as
    the record checks it."""
    f = RunSettings.model_fields[name]
    one = Annotated[(f.annotation, *f.metadata)] if f.metadata else f.annotation
    return (one | None, Field(None, description=f.description))  # type: ignore[operator]


#: Each settings field a sweep file sets by a key of its own, by that key (the field's
#: sweep name: ``preferences`` is the preferences file; the LLM's are under ``llm``).
SWEPT: dict[str, str] = {door(n).sweep or n: n for n in RunSettings.model_fields
                         if n not in _NOT_SWEPT and "." not in (door(n).sweep or "")}


#: The keys of an ``llm`` entry, each the settings field its sweep name puts under ``llm``.
LLM_KEYS: dict[str, str] = {door(n).sweep.partition(".")[2]: n  # type: ignore[union-attr]
                            for n in RunSettings.model_fields
                            if (door(n).sweep or "").startswith("llm.")}

class _LLMEntry(BaseModel):
    """One LLM: the settings ``llm``, ``model``, ``base_url``, ``replay`` and
    ``temperature`` under their sweep names (a key left out takes the bench's default);
    ``name`` labels it in cell names (default: backend and model)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: Text | None = None

    @property
    def label(self) -> str:
        """How the entry is named in a cell's name."""
        backend, model = self.backend, self.model  # type: ignore[attr-defined]
        return self.name or (backend or "embedded") + (
            f"-{Path(model).name}" if model else "")


#: One LLM of a sweep file (:class:`_LLMEntry`), its keys made from the settings record.
LLMEntry = create_model(  # type: ignore[call-overload]
    "LLMEntry", __base__=_LLMEntry,
    **{key: _setting_field(name) for key, name in LLM_KEYS.items()})


#: The keys whose value is itself a list (a setting that holds several).
_MANY = tuple(key for key, name in SWEPT.items()
              if RunSettings.model_fields[name].default == ())


class _Experiment(BaseModel):
    """A cell's keys that are no setting of a run: which tasks, methods and trials, and
    whether to draw each trial's final table."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    tasks: Tasks | None = None
    methods: Text | list[Text] | None = None
    trials: Annotated[int, Field(ge=1)] | None = None
    images: bool | None = None
    llm: LLMEntry | None = None


#: One cell's settings, in the bench's terms: :class:`_Experiment`'s keys and every field
#: of the settings record (:data:`SWEPT`; units as the record's help says: ``weight``
#: seconds, ``fidelity_weight`` seconds per centimetre). A key left out, or ``null``,
#: takes the bench's default; for ``chairs`` and ``table`` (also ``table: scene``) that is
#: the scene's own.
Values = create_model(  # type: ignore[call-overload]
    "Values", __base__=_Experiment,
    **{key: _setting_field(name) for key, name in SWEPT.items()})


def _as_list(value: Any) -> Any:
    """A grid key's single value read as a list of one (``chairs: 4`` is ``chairs: [4]``);
    ``null`` stays, to be refused as no values."""
    return value if value is None or isinstance(value, list) else [value]


def _grid_field(f: Any) -> tuple[Any, Any]:
    """A :class:`Values` field as a grid key: a non-empty list of its values (or one value,
    a list of one), each checked as the field is."""
    one = Annotated[(f.annotation, *f.metadata)] if f.metadata else f.annotation
    return (Annotated[list[one] | None, BeforeValidator(_as_list)],  # type: ignore[valid-type]
            Field(None, min_length=1))


#: What ``grid`` may vary: each key of :class:`Values`, as a non-empty list of its values.
Grid = create_model(  # type: ignore[call-overload]
    "Grid", __config__=ConfigDict(extra="forbid", frozen=True),
    **{name: _grid_field(f) for name, f in Values.model_fields.items()})


class SweepFile(Values):  # type: ignore[misc, valid-type]
    """A sweep file: the values every cell shares, and the ``grid`` of those that vary."""

    grid: Grid = Field(default_factory=Grid)  # type: ignore[valid-type]

    @field_validator(*(k for k in Values.model_fields if k not in ("tasks", "methods")
                       and k not in _MANY), mode="before")
    @classmethod
    def _one_value(cls, value: Any, info: ValidationInfo) -> Any:
        # A list at the top level is most likely meant as the grid's.
        if isinstance(value, list):
            raise ValueError("one value here, not a list; to run each value, put "
                             f"{info.field_name} under grid")
        return value


@dataclass(frozen=True)
class SweepCell:
    """One combination: its directory ``name``, the grid's ``axes`` (key -> the value's
    label) and its :class:`Values`."""

    name: str
    axes: Mapping[str, str]
    values: Values  # type: ignore[valid-type]


@dataclass(frozen=True)
class Sweep:
    """A sweep file read: where it lies (``base``, the directory its paths are relative
    to), the grid's keys in the file's order, and every cell."""

    path: Path
    axes: tuple[str, ...]
    cells: tuple[SweepCell, ...]

    @property
    def base(self) -> Path:
        """The directory the file's paths are relative to."""
        return self.path.parent


def load_sweep(path: Path) -> Sweep:
    """Read and expand the sweep file ``path``; :class:`BadInput` names the file and the
    field for anything wrong."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise BadInput(f"{path}: sweep file not found") from None
    except UnicodeDecodeError:
        raise BadInput(f"{path}: not UTF-8 text") from None
    except OSError as exc:
        raise BadInput(f"{path}: cannot read ({exc.strerror or exc})") from None
    doc = load_yaml_model(text, str(path), SweepFile, "", "name")
    axes = tuple(k for k in _raw_grid(text) if k in doc.grid.model_fields_set)
    for key in axes:
        if getattr(doc.grid, key) is None:
            raise BadInput(f"{path}: grid.{key}: no values; give a list, or leave the key out")
        if key in doc.model_fields_set:
            raise BadInput(f"{path}: {key}: both in grid and at the top level; give it in one "
                           "place")
    shared = {k: getattr(doc, k) for k in doc.model_fields_set if k != "grid"}
    cells = []
    for combo in itertools.product(*(getattr(doc.grid, k) for k in axes)):
        chosen = dict(zip(axes, combo, strict=True))
        labels = {k: _label(k, v) for k, v in chosen.items()}
        cells.append(SweepCell(_name(labels), labels, Values(**shared, **chosen)))
    seen: dict[str, SweepCell] = {}
    for cell in cells:
        # Case-blind: on some file systems two such names are one directory.
        other = seen.get(cell.name.casefold())
        if other is not None:
            raise BadInput(f"{path}: grid: two cells would share the directory "
                           f"{cell.name!r} ({dict(other.axes)} and {dict(cell.axes)}); make "
                           "the values distinct (an llm entry takes a name)")
        seen[cell.name.casefold()] = cell
    return Sweep(path, axes, tuple(cells))


def cell_dirs(out: Path) -> list[Path]:
    """The cells of the sweep directory ``out`` that hold trials, in the sweep's order
    (its :data:`MARKER` file's, then any other by name); empty for a directory that holds
    no bench results below it."""
    from llm_grop.experiment.rows import ROWS

    named: list[str] = []
    try:
        doc = json.loads((out / MARKER).read_text(encoding="utf-8"))
        named = [c["name"] for c in doc["cells"] if isinstance(c.get("name"), str)]
    except (OSError, ValueError, LookupError, TypeError, AttributeError, RecursionError):
        pass  # no marker, or not one this version wrote: the directories still tell
    try:
        found = sorted(p.name for p in out.iterdir() if p.is_dir())
    except OSError:
        found = []
    names = dict.fromkeys([*named, *found])
    return [out / n for n in names
            if n not in ("", "..") and Path(n).name == n and (out / n / ROWS).is_file()]


def _raw_grid(text: str) -> list[str]:
    """The grid's keys in the order the file gives them (the model's order is its own;
    the small file is parsed again rather than threading the raw mapping through)."""
    import yaml

    raw = yaml.safe_load(text)
    grid = raw.get("grid") if isinstance(raw, dict) else None
    return list(grid) if isinstance(grid, dict) else []


def _label(key: str, value: Any) -> str:
    """The grid value ``value`` of ``key`` as it reads in a cell's name."""
    if isinstance(value, LLMEntry):
        return value.label
    if value is None:
        return "scene" if key in ("chairs", "table", "scene") else "default"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, list):
        return "+".join(_label(key, v) for v in value)
    return str(value)


def _name(labels: Mapping[str, str]) -> str:
    """A cell's directory name: ``key=value`` pairs joined by commas, made safe for a
    file system; ``all`` for a sweep without a grid."""
    if not labels:
        return "all"
    name = ",".join(f"{k}={_UNSAFE.sub('_', v).strip('.')}" for k, v in labels.items())
    if len(name) > MAX_NAME:
        import hashlib

        name = name[:MAX_NAME - 9] + "-" + hashlib.sha256(name.encode()).hexdigest()[:8]
    return name
