"""Symbolic spatial relations, named with the paper's phrases (the contract's names).

What each relation means is one table, ``relations.yaml`` beside this module: per
relation its contract name, its ASP constant, the subject's state against the reference
on each axis of the table frame (``less``, ``aligned`` or ``greater``; +x to the diner's
right, +y away from the diner), whether it stacks, and its converse. It is read and
checked once, at import; every name below is derived from it, and so are clingo's facts
(:mod:`llm_grop.arrangement.consistency`) and the sampler's tests
(:mod:`llm_grop.arrangement.predicates`).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from types import MappingProxyType
from typing import Any, Literal, cast

import yaml

#: The table frame's axes: ``x`` (+x to the diner's right), ``y`` (+y away from the diner).
AXES: tuple[Literal["x", "y"], ...] = ("x", "y")

AxisState = Literal["less", "aligned", "greater"]
#: A subject's states against its reference on one axis.
AXIS_STATES: tuple[AxisState, ...] = ("less", "aligned", "greater")

Rests = Literal["subject", "reference"]
#: Who rests on whom in a stacking relation: the subject on the reference, or the reverse.
RESTS: tuple[Rests, ...] = ("subject", "reference")

_SIGN: dict[AxisState, int] = {"less": -1, "aligned": 0, "greater": 1}
_MIRROR: dict[AxisState, AxisState] = {"less": "greater", "aligned": "aligned",
                                       "greater": "less"}
_SWAP: dict[Rests | None, Rests | None] = {"subject": "reference", "reference": "subject",
                                           None: None}
#: An ASP constant: a lowercase identifier (anything else would not be a constant).
_ASP_CONSTANT = re.compile(r"[a-z][a-z0-9_]*")
_KEYS = frozenset({"name", "asp", "x", "y", "rests", "converse", "reference"})


@dataclass(frozen=True)
class Meaning:
    """What one relation means, as ``relations.yaml`` states it.

    ``name`` is the contract's name and ``asp`` the constant clingo uses for it. ``x`` and
    ``y`` are the subject's state against the reference on each axis (:data:`AXIS_STATES`);
    ``rests`` says who rests on whom in a stacking relation (:data:`RESTS`, ``None`` for
    the others); ``converse`` names the relation that holds the other way round. The one
    relation without a reference (``center``) has ``reference`` false and none of these.
    """

    name: str
    asp: str
    x: AxisState | None = None
    y: AxisState | None = None
    rests: Rests | None = None
    converse: str | None = None
    reference: bool = True

    def state(self, axis: str) -> AxisState:
        """The subject's state on ``axis`` (``"x"`` or ``"y"``)."""
        got = self.x if axis == "x" else self.y if axis == "y" else None
        if got is None:
            raise ValueError(f"{self.name!r} has no state on axis {axis!r}")
        return got

    @property
    def direction(self) -> tuple[int, int]:
        """The states as signs ``(x, y)``: -1 less, 0 aligned, +1 greater."""
        return (_SIGN[self.state("x")], _SIGN[self.state("y")])


def _fail(where: str, at: str, reason: str) -> ValueError:
    return ValueError(f"{where}: {at}: {reason}")


def _entry(raw: object, k: int, where: str) -> Meaning:
    """One table entry, checked on its own."""
    if not isinstance(raw, dict):
        raise _fail(where, f"relations[{k}]", "expected a mapping")
    name = raw.get("name")
    if not isinstance(name, str) or not name.strip() or name != name.strip():
        raise _fail(where, f"relations[{k}].name", f"expected a non-empty name, got {name!r}")
    at = f"relations[{k}] ({name!r})"
    unknown = sorted(str(key) for key in raw if key not in _KEYS)
    if unknown:
        raise _fail(where, at, f"unknown field {unknown[0]!r}")
    asp = raw.get("asp")
    if not isinstance(asp, str) or not _ASP_CONSTANT.fullmatch(asp) or asp == "not":
        raise _fail(where, f"{at}.asp", f"expected a lowercase identifier, got {asp!r}")
    reference = raw.get("reference", True)
    if not isinstance(reference, bool):
        raise _fail(where, f"{at}.reference", f"expected true or false, got {reference!r}")
    if not reference:
        extra = [f for f in ("x", "y", "rests", "converse") if f in raw]
        if extra:
            raise _fail(where, f"{at}.{extra[0]}", "a relation without a reference has none")
        return Meaning(name, asp, reference=False)
    states = []
    for axis in AXES:
        state = raw.get(axis)
        if state not in AXIS_STATES:
            raise _fail(where, f"{at}.{axis}", f"expected one of {', '.join(AXIS_STATES)}, "
                        f"got {state!r}")
        states.append(cast(AxisState, state))
    rests = raw.get("rests")
    if rests is not None and rests not in RESTS:
        raise _fail(where, f"{at}.rests", f"expected one of {', '.join(RESTS)}, got {rests!r}")
    if rests is not None and states != ["aligned", "aligned"]:
        raise _fail(where, at, "a resting pair is aligned on both axes")
    converse = raw.get("converse")
    if not isinstance(converse, str):
        raise _fail(where, f"{at}.converse", f"expected a relation's name, got {converse!r}")
    return Meaning(name, asp, states[0], states[1], cast(Rests | None, rests), converse)


def parse_meanings(text: str, where: str = "relations.yaml") -> tuple[Meaning, ...]:
    """The relations table in ``text`` (YAML), in its order, checked as a whole.

    Raises :class:`ValueError` naming ``where`` and the entry when the table is broken:
    unknown or missing fields, a repeated name or ASP constant, a converse that is not
    symmetric or whose states are not mirrored, two relations with one meaning, or not
    exactly one relation without a reference.
    """
    try:
        raw: Any = yaml.safe_load(text)
    except yaml.YAMLError:
        raise ValueError(f"{where}: not valid YAML") from None
    entries = raw.get("relations") if isinstance(raw, dict) else None
    if not isinstance(entries, list) or not entries:
        raise ValueError(f"{where}: expected a mapping with a non-empty 'relations' list")
    meanings = [_entry(e, k, where) for k, e in enumerate(entries)]
    by_name: dict[str, Meaning] = {}
    asp: set[str] = set()
    said: dict[tuple[object, ...], str] = {}
    for k, m in enumerate(meanings):
        at = f"relations[{k}] ({m.name!r})"
        if m.name in by_name:
            raise _fail(where, at, "the name is used twice")
        if m.asp in asp:
            raise _fail(where, f"{at}.asp", f"the constant {m.asp!r} is used twice")
        meaning = (m.x, m.y, m.rests, m.reference)
        if meaning in said:
            raise _fail(where, at, f"means the same as {said[meaning]!r}")
        by_name[m.name], said[meaning] = m, m.name
        asp.add(m.asp)
    for k, m in enumerate(meanings):
        if not m.reference:
            continue
        at = f"relations[{k}] ({m.name!r}).converse"
        c = by_name.get(cast(str, m.converse))
        if c is None or not c.reference:
            raise _fail(where, at, f"{m.converse!r} is not a relation with a reference")
        if c.converse != m.name:
            raise _fail(where, at, f"the converse of {c.name!r} is {c.converse!r}, not "
                        f"{m.name!r}")
        if (c.x, c.y, c.rests) != (_MIRROR[m.state("x")], _MIRROR[m.state("y")],
                                   _SWAP[m.rests]):
            raise _fail(where, at, f"{c.name!r} must mirror its states (less <-> greater) "
                        "and swap who rests on whom")
    if sum(not m.reference for m in meanings) != 1:
        raise ValueError(f"{where}: exactly one relation must be without a reference")
    return tuple(meanings)


def _load() -> tuple[Meaning, ...]:
    text = resources.files("llm_grop.world").joinpath("relations.yaml").read_text("utf-8")
    return parse_meanings(text, "packaged relations.yaml")


#: What each relation means, by contract name, in the order Template 1 lists them.
MEANINGS: Mapping[str, Meaning] = MappingProxyType({m.name: m for m in _load()})


def _named(reference: bool = True, x: AxisState | None = None, y: AxisState | None = None,
           rests: Rests | None = None) -> str:
    """The name of the relation with this meaning (the table holds one at most)."""
    for m in MEANINGS.values():
        if (m.reference, m.x, m.y, m.rests) == (reference, x, y, rests):
            return m.name
    raise ValueError(f"relations.yaml: no relation means x {x}, y {y}, rests {rests}, "
                     f"reference {reference}")


LEFT = _named(x="less", y="aligned")
RIGHT = _named(x="greater", y="aligned")
ABOVE = _named(x="aligned", y="greater")
BELOW = _named(x="aligned", y="less")
ABOVE_LEFT = _named(x="less", y="greater")
ABOVE_RIGHT = _named(x="greater", y="greater")
BELOW_LEFT = _named(x="less", y="less")
BELOW_RIGHT = _named(x="greater", y="less")
ON_TOP_OF = _named(x="aligned", y="aligned", rests="subject")
UNDER = _named(x="aligned", y="aligned", rests="reference")
CENTER = _named(reference=False)

#: Every relation name, in the order Template 1 lists them.
RELATION_NAMES: tuple[str, ...] = tuple(MEANINGS)

#: The relation that holds the other way round: ``X r Y`` iff ``Y CONVERSE[r] X``.
CONVERSE: dict[str, str] = {n: m.converse for n, m in MEANINGS.items() if m.converse}

#: Unit direction of the subject from the reference in the table frame (+x right, +y above):
#: each axis's state as a sign (-1 less, 0 aligned, +1 greater).
DIRECTION: dict[str, tuple[int, int]] = {n: m.direction for n, m in MEANINGS.items()
                                         if m.reference}

#: Relations that stack one object on another.
STACKING = frozenset(n for n, m in MEANINGS.items() if m.rests is not None)

#: Contract relation name -> the ASP constant clingo's facts use for it.
ASP_NAME: dict[str, str] = {n: m.asp for n, m in MEANINGS.items()}

#: Where a relation came from: the LLM's answer, a preference the user stated
#: (``--prefer`` or a preferences file), or the request's own words ("a mug on a coaster").
SOURCES: tuple[str, ...] = ("llm", "preference", "request", "revision", "learned")


@dataclass(frozen=True)
class Relation:
    """``subject relation reference``, e.g. dinner fork / to the left of / dinner plate.

    ``reference`` is ``None`` for ``center`` (the subject is at the table's centre).
    ``line`` is the text the relation was read from: the LLM's line, a preference's
    sentence, or the request's words. ``source`` is one of :data:`SOURCES`. ``gap_m`` is a
    distance the user stated for it (the gap between the objects' edges, metres), else
    ``None``. ``revision`` is the round of the feedback loop whose answer first stated it
    (:mod:`llm_grop.world.failure`; its ``source`` is then ``"revision"``), ``None`` for
    the LLM's first answer and other sources. ``learned_from`` names the example settings
    a learned relation was read off (``source`` ``"learned"``;
    :mod:`llm_grop.arrangement.learning`).
    """

    subject: str
    relation: str
    reference: str | None
    line: str = ""
    source: str = "llm"
    gap_m: float | None = None
    revision: int | None = None
    learned_from: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.relation not in RELATION_NAMES:
            raise ValueError(f"unknown relation {self.relation!r}")
        if (self.relation == CENTER) != (self.reference is None):
            raise ValueError("'center' takes no reference; every other relation needs one")
        if self.source not in SOURCES:
            raise ValueError(f"unknown relation source {self.source!r}")

    def sentence(self) -> str:
        """The relation as a Template 1 line: ``Place the X to the left of the Y.``"""
        if self.relation == CENTER:
            return f"Place the {self.subject} in the center of the table."
        return f"Place the {self.subject} {self.relation} the {self.reference}."

    def converse(self) -> Relation:
        """The same fact said from the reference's side (not defined for ``center``)."""
        if self.reference is None:
            raise ValueError("'center' has no converse")
        return Relation(self.reference, CONVERSE[self.relation], self.subject, self.line,
                        self.source, self.gap_m, self.revision, self.learned_from)

    def key(self) -> tuple[str, str, str | None]:
        """``(subject, relation, reference)`` without the source line."""
        return (self.subject, self.relation, self.reference)


@dataclass(frozen=True)
class Choice:
    """An ambiguous stated relation: exactly one of ``options`` holds, each option a tuple of
    relations that hold together; ``words`` are the request's words it was read from.

    "The knife beside the plate" is two options of one relation each (left of, right of);
    "the fork and the knife either side of the plate" is two options of two relations.
    Raises :class:`ValueError` for no options or an empty option.
    """

    options: tuple[tuple[Relation, ...], ...]
    words: str = ""

    def __post_init__(self) -> None:
        # Lists are accepted and kept as tuples, so that a choice stays hashable.
        options = tuple(tuple(option) for option in self.options)
        if not options or not all(options):
            raise ValueError("a choice needs at least one option, and each option a relation")
        if not all(isinstance(r, Relation) for option in options for r in option):
            raise ValueError("a choice's options hold relations")
        object.__setattr__(self, "options", options)


def dedupe(relations: Sequence[Relation]) -> tuple[Relation, ...]:
    """``relations`` without repeats of a fact, also when restated as its converse (the
    first statement is kept)."""
    seen: set[tuple[str, str, str | None]] = set()
    out = []
    for r in relations:
        if r.key() in seen:
            continue
        seen.add(r.key())
        if r.reference is not None:
            seen.add(r.converse().key())
        out.append(r)
    return tuple(out)
