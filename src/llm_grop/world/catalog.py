"""The object catalog: shapes, footprints, heights and synonyms of table objects.

The package ships ``data/catalog.yaml``; users extend it with files of their own
(same layout), which may add objects or override packaged ones by name (a later file
wins). Within one file, every name and synonym must be unique: two entries with the same
name, or a name or synonym that another entry of the file already uses, are refused.
"""

from __future__ import annotations

import difflib
import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

from llm_grop.datafile import load_yaml_model
from llm_grop.errors import CatalogError, UnknownObject

#: Environment variable holding extra catalog files, separated by ``os.pathsep``.
CATALOG_ENV = "LLM_GROP_CATALOG"

#: The most objects of one kind a catalog may let wait in one pile.
MAX_STACK = 12
_ARTICLES = re.compile(r"^(?:the|a|an|one|some|another)\s+")
#: A trailing instance number: "dinner fork 2" is the second instance of "dinner fork".
_INSTANCE_NUMBER = re.compile(r"\s+\d+$")


@dataclass(frozen=True)
class ObjectSpec:
    """A kind of table object.

    ``size`` is the footprint ``(sx, sy)`` in metres in the object's own frame;
    ``height`` is in metres. ``shape`` is ``"circle"`` (then ``sx == sy`` is the
    diameter) or ``"box"``. ``stack`` is how many of this kind may wait in one pile on a
    supply table before an episode (plates and bowls nest; 1: each waits on its own).
    """

    name: str
    shape: Literal["circle", "box"]
    size: tuple[float, float]
    height: float
    synonyms: tuple[str, ...] = ()
    stack: int = 1

    @property
    def area(self) -> float:
        """Footprint area in square metres."""
        sx, sy = self.size
        return 3.141592653589793 * sx * sx / 4 if self.shape == "circle" else sx * sy


class _ObjectModel(BaseModel):
    model_config = ConfigDict(extra="forbid")

    name: str = Field(min_length=1)
    shape: Literal["circle", "box"]
    size: tuple[float, float]
    height: float = Field(gt=0, allow_inf_nan=False)
    synonyms: list[str] = []
    stack: int = Field(1, ge=1, le=MAX_STACK)

    @field_validator("size")
    @classmethod
    def _positive(cls, v: tuple[float, float]) -> tuple[float, float]:
        if not all(math.isfinite(s) and s > 0 for s in v):
            raise ValueError("size must be positive and finite")
        return v


class _CatalogModel(BaseModel):
    model_config = ConfigDict(extra="forbid")

    objects: list[_ObjectModel]


def normalize_name(text: str) -> str:
    """Lower case, single spaces, no leading article or trailing punctuation."""
    text = re.sub(r"[^a-z0-9' -]+", " ", text.lower().replace("-", " "))
    text = re.sub(r"\s+", " ", text).strip(" '")
    return _ARTICLES.sub("", text)


def instance_kind(name: str) -> str:
    """The kind an instance's name is numbered from: ``"dinner fork 2"`` -> ``"dinner fork"``
    (a name without a trailing number is returned as it is)."""
    return _INSTANCE_NUMBER.sub("", name)


def singular_forms(name: str) -> list[str]:
    """``name`` and the singular forms its last word might have (knives -> knife)."""
    head, _, last = name.rpartition(" ")
    prefix = f"{head} " if head else ""
    forms = [name]
    if last.endswith("ies") and len(last) > 4:
        forms.append(prefix + last[:-3] + "y")
    if last.endswith("ves"):
        forms += [prefix + last[:-3] + "fe", prefix + last[:-3] + "f"]
    if last.endswith("es"):
        forms.append(prefix + last[:-2])
    if last.endswith("s") and not last.endswith("ss"):
        forms.append(prefix + last[:-1])
    return forms


class Catalog:
    """An immutable set of :class:`ObjectSpec`, looked up by name, synonym or plural."""

    def __init__(self, specs: Iterable[ObjectSpec]) -> None:
        self._specs: dict[str, ObjectSpec] = {}
        for spec in specs:
            self._specs[spec.name] = spec
        self._aliases: dict[str, str] = {}
        for spec in self._specs.values():
            for alias in spec.synonyms:
                self._aliases.setdefault(normalize_name(alias), spec.name)
        for name in self._specs:
            self._aliases[name] = name

    @classmethod
    def load(cls, extra_files: Sequence[str | os.PathLike[str]] = (), *, use_env: bool = True
             ) -> Catalog:
        """The packaged catalog, extended by ``extra_files`` and ``$LLM_GROP_CATALOG``."""
        packaged = resources.files("llm_grop").joinpath("data/catalog.yaml")
        specs = _parse(packaged.read_text(encoding="utf-8"), "packaged catalog")
        files = list(extra_files)
        if use_env and os.environ.get(CATALOG_ENV):
            files = [p for p in os.environ[CATALOG_ENV].split(os.pathsep) if p] + files
        for path in files:
            try:
                text = Path(path).read_text(encoding="utf-8")
            except OSError as exc:
                raise CatalogError(f"catalog {path}: cannot read ({exc.strerror})") from None
            except UnicodeDecodeError:
                raise CatalogError(f"catalog {path}: cannot read (not UTF-8 text)") from None
            specs += _parse(text, f"catalog {path}")
        return cls(specs)

    @classmethod
    def from_text(cls, text: str, where: str = "catalog") -> Catalog:
        """The objects of one catalog file's YAML ``text`` alone (no packaged ones); errors
        are :class:`CatalogError` naming ``where``."""
        return cls(_parse(text, where))

    @property
    def specs(self) -> Mapping[str, ObjectSpec]:
        """Every spec by canonical name."""
        return dict(self._specs)

    def names(self) -> list[str]:
        """Canonical names, sorted."""
        return sorted(self._specs)

    def aliases(self) -> Mapping[str, str]:
        """Every known name or synonym (normalised) -> canonical name."""
        return dict(self._aliases)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self.lookup(name) is not None

    def __len__(self) -> int:
        return len(self._specs)

    def lookup(self, text: str) -> ObjectSpec | None:
        """The spec that ``text`` names (canonical, synonym or plural), else ``None``."""
        for form in singular_forms(normalize_name(text)):
            if form in self._aliases:
                return self._specs[self._aliases[form]]
        return None

    def suggest(self, text: str, n: int = 3) -> list[str]:
        """The canonical names closest to ``text``, best first."""
        close = difflib.get_close_matches(normalize_name(text), list(self._aliases), n=n * 2,
                                          cutoff=0.5)
        out: list[str] = []
        for alias in close:
            name = self._aliases[alias]
            if name not in out:
                out.append(name)
        return out[:n]

    def resolve(self, text: str, where: str = "request") -> ObjectSpec:
        """Like :meth:`lookup`, but raises :class:`UnknownObject` with suggestions."""
        spec = self.lookup(text)
        if spec is None:
            raise UnknownObject(normalize_name(text) or text, self.suggest(text), where)
        return spec


def _parse(text: str, where: str) -> list[ObjectSpec]:
    model = load_yaml_model(text, where, _CatalogModel, "objects", "name", CatalogError)
    specs = []
    for i, obj in enumerate(model.objects):
        name = normalize_name(obj.name)
        if not name:
            raise CatalogError(f"{where}: objects[{i}] ({obj.name!r}).name: "
                               "needs letters or digits")
        if obj.shape == "circle" and abs(obj.size[0] - obj.size[1]) > 1e-9:
            raise CatalogError(f"{where}: objects[{i}] ({obj.name!r}).size: "
                               "a circle needs size [d, d]")
        specs.append(ObjectSpec(name, obj.shape, (float(obj.size[0]), float(obj.size[1])),
                                float(obj.height), tuple(obj.synonyms), obj.stack))
    _check_unique(model.objects, specs, where)
    return specs


def _check_unique(objects: Sequence[_ObjectModel], specs: Sequence[ObjectSpec], where: str
                  ) -> None:
    """Raises :class:`CatalogError` for the first name or synonym (normalised) that two
    entries of one file share, naming both entries; within one entry repeats are harmless."""
    # Normalised name or synonym -> (entry index, whether it is that entry's name).
    used: dict[str, tuple[int, bool]] = {}

    def taken(text: str, j: int, is_name: bool) -> str:
        kind = "the name" if is_name else "a synonym"
        return f"{text!r} is already {kind} of objects[{j}] ({objects[j].name!r})"

    for i, (obj, spec) in enumerate(zip(objects, specs, strict=True)):
        label = f"{where}: objects[{i}] ({obj.name!r})"
        j, is_name = used.get(spec.name, (i, True))
        if j != i and is_name:
            raise CatalogError(f"{label}: duplicate name; objects[{j}] is already "
                               f"{spec.name!r}")
        if j != i:
            raise CatalogError(f"{label}: name {taken(spec.name, j, is_name)}")
        used[spec.name] = (i, True)
        for synonym in obj.synonyms:
            alias = normalize_name(synonym)
            if not alias:
                continue  # names nothing ("!!"): lookups never reach it
            j, is_name = used.get(alias, (i, False))
            if j != i:
                raise CatalogError(f"{label}.synonyms: {taken(synonym, j, is_name)}")
            used.setdefault(alias, (i, False))
