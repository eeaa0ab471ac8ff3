"""The target table and its frame.

Table frame (the contract's): origin at the centre of the table top, +x to the
diner's right, +y away from the diner. The diner sits at the -y edge. A table set for
several diners lists their seats (``diners``, poses in the table frame); each diner's
setting is arranged in that diner's own frame (:mod:`llm_grop.geometry.places`).

A table top is a rectangle (``width`` along x, ``depth`` along y) or a circle whose
``width`` and ``depth`` are both its diameter, as the contract writes it (``size``
``[d, d]``); for a round table the diner's edge is the point ``(0, -radius)``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from decimal import Decimal
from typing import Literal, get_args

from llm_grop.errors import BadInput
from llm_grop.world.seat import Seat

DEFAULT_TABLE_SIZE_M = (0.9, 0.6)

TableShape = Literal["rectangle", "circle"]
#: The shapes a table top may have, as the contract names them.
TABLE_SHAPES: tuple[str, ...] = get_args(TableShape)

#: The smallest and the largest side (width, depth or diameter) of a dining table top that
#: ``--table`` accepts, metres: anything outside is a typo or a unit mix-up (``120x80``).
MIN_TABLE_SIDE_M = 0.3
MAX_TABLE_SIDE_M = 10.0
#: The units a ``--table`` size may be written in, as the power of ten that turns one into
#: metres (a bare number is metres).
TABLE_UNIT_EXPONENTS: dict[str, int] = {"m": 0, "cm": -2, "mm": -3}
#: The units tried, in order, for the "did you mean" hint of an implausible size.
_HINT_UNITS = ("cm", "mm", "m")

_NUMBER = r"\s*([0-9]*\.?[0-9]+)\s*(mm|cm|m)?\s*"
_RECTANGLE_TEXT = re.compile(_NUMBER + r"[xX×*]" + _NUMBER, re.IGNORECASE)
_ROUND_TEXT = re.compile(r"\s*round\s*:" + _NUMBER, re.IGNORECASE)
_UNITS_HELP = "a unit may follow: 120x80cm, 1.2x0.8m, 1200x800mm, round:120cm"
#: A seat this far (metres) inside the top still counts as at its edge.
_SEAT_TOL_M = 1e-3
#: How far width and depth of a round top may differ (metres): JSON rounds to 0.1 mm.
_ROUND_TOL_M = 1e-6


@dataclass(frozen=True)
class Table:
    """A table top: ``width`` along x and ``depth`` along y, in metres.

    ``shape`` is ``"rectangle"`` or ``"circle"``; a circle's ``width`` and ``depth`` are
    both its diameter. Raises :class:`BadInput` for a size that is not positive, an
    unknown shape, or a circle given in a rectangular frame (``width != depth``).
    """

    width: float = DEFAULT_TABLE_SIZE_M[0]
    depth: float = DEFAULT_TABLE_SIZE_M[1]
    shape: str = "rectangle"
    diners: tuple[Seat, ...] = ()

    def __post_init__(self) -> None:
        if not (0 < self.width < math.inf and 0 < self.depth < math.inf):
            raise BadInput(f"size must be positive and finite, got {self.width} x "
                           f"{self.depth} m", param="table")
        if self.shape not in TABLE_SHAPES:
            raise BadInput(f"shape must be one of {', '.join(TABLE_SHAPES)}, "
                           f"got {self.shape!r}", param="table")
        if self.is_round and not math.isclose(self.width, self.depth, rel_tol=0.0,
                                              abs_tol=_ROUND_TOL_M):
            raise BadInput(f"a round table has one size, its diameter, but was given "
                           f"{self.width:g} x {self.depth:g} m; use [d, d]", param="table")
        for k, seat in enumerate(self.diners):
            if self._inside(seat.x, seat.y):
                raise BadInput(f"diner {k}'s seat at ({seat.x:+.2f}, {seat.y:+.2f}) m lies "
                               f"inside the {self.label}; a seat goes at or beyond its edge",
                               param="table")

    def _inside(self, x: float, y: float, tol: float = _SEAT_TOL_M) -> bool:
        """Whether ``(x, y)`` lies inside the top by more than ``tol`` metres."""
        if self.is_round:
            return math.hypot(x, y) < self.width / 2 - tol
        return abs(x) < self.width / 2 - tol and abs(y) < self.depth / 2 - tol

    @property
    def seats(self) -> tuple[Seat, ...]:
        """Where the diners sit: ``diners``, else the contract's one diner at the -y edge."""
        return self.diners or (Seat(0.0, -self.depth / 2, math.pi / 2),)

    def with_diners(self, diners: tuple[Seat, ...]) -> Table:
        """This top with ``diners`` seated round it."""
        return Table(self.width, self.depth, self.shape, tuple(diners))

    @classmethod
    def circle(cls, diameter: float) -> Table:
        """A round top of ``diameter`` metres."""
        return cls(diameter, diameter, "circle")

    @property
    def size(self) -> tuple[float, float]:
        """``(width, depth)`` in metres (``(d, d)`` for a round top)."""
        return (self.width, self.depth)

    @property
    def is_round(self) -> bool:
        """Whether the top is a circle."""
        return self.shape == "circle"

    @property
    def radius(self) -> float:
        """A round top's radius, metres. Raises ``ValueError`` for a rectangle."""
        if not self.is_round:
            raise ValueError("a rectangular table has no radius")
        return self.width / 2

    @property
    def area(self) -> float:
        """The top's area, square metres."""
        return math.pi * self.width * self.width / 4 if self.is_round \
            else self.width * self.depth

    @property
    def label(self) -> str:
        """The top in words for messages: ``0.9 x 0.6 m table``, ``round 1.2 m table``."""
        if self.is_round:
            return f"round {self.width:g} m table"
        return f"{self.width:g} x {self.depth:g} m table"

    @property
    def text(self) -> str:
        """The top as :meth:`parse` reads it: ``0.9x0.6`` or ``round:1.2``."""
        w, d = float(self.width), float(self.depth)  # repr: the shortest exact spelling
        return f"round:{w!r}" if self.is_round else f"{w!r}x{d!r}"

    @classmethod
    def parse(cls, text: str) -> Table:
        """A table from ``"WxD"`` or ``"round:D"`` (a round top of diameter ``D``).

        Sizes are metres (``"0.9x0.6"``, ``"round:1.2"``) unless a unit follows them:
        ``"120x80cm"``, ``"1.2x0.8m"``, ``"1200x800mm"``, ``"round:120cm"``; a unit after
        the second side applies to both. Each side must lie between
        :data:`MIN_TABLE_SIDE_M` and :data:`MAX_TABLE_SIDE_M` metres, so that a size in
        the wrong unit (``"120x80"``, 120 x 80 m) is refused with a hint rather than used.
        Raises :class:`BadInput` (one line, naming the ``table`` parameter) otherwise.
        """
        if text.strip().lower().startswith("round"):
            m = _ROUND_TEXT.fullmatch(text)
            if not m:
                raise BadInput(f"a round table has one size, its diameter in metres: "
                               f"round:D such as round:1.2 ({_UNITS_HELP}), got {text!r}",
                               param="table")
            sides = [(m.group(1), m.group(2))]
            table = cls.circle(*_metres(sides))
        else:
            m = _RECTANGLE_TEXT.fullmatch(text)
            if not m:
                raise BadInput(f"expected WxD in metres such as 0.9x0.6, or round:D "
                               f"such as round:1.2 ({_UNITS_HELP}), got {text!r}",
                               param="table")
            sides = [(m.group(1), m.group(2)), (m.group(3), m.group(4))]
            table = cls(*_metres(sides))
        _check_plausible(table, sides)
        return table


_Side = tuple[str, str | None]
"""One side as written in ``--table``: its number and its unit (``None``: as the other's,
else metres)."""


def _units(sides: list[_Side]) -> list[str]:
    """Each side's unit: its own, else the last side's (``120x80cm``), else metres."""
    last = sides[-1][1]
    if len(sides) > 1 and sides[0][1] is not None and last is None:
        (w, unit), (d, _) = sides
        raise BadInput(f"{w}{unit}x{d} gives a unit for the first side only; "
                       f"write {w}x{d}{unit.lower()}", param="table")
    return [(unit or last or "m").lower() for _, unit in sides]


def _metres(sides: list[_Side]) -> list[float]:
    """The sides in metres."""
    return [_in_metres(number, unit)
            for (number, _), unit in zip(sides, _units(sides), strict=True)]


def _in_metres(number: str, unit: str) -> float:
    """``number`` ``unit`` in metres, converted in decimal (``1200 mm`` is exactly ``1.2``)."""
    return float(Decimal(number).scaleb(TABLE_UNIT_EXPONENTS[unit]))


def _plausible(sizes_m: list[float]) -> bool:
    """Whether every side, metres, is one a dining table has."""
    return all(MIN_TABLE_SIDE_M <= s <= MAX_TABLE_SIDE_M for s in sizes_m)


def _check_plausible(table: Table, sides: list[_Side]) -> None:
    """:class:`BadInput` with a "did you mean" hint for a top no dining table has."""
    sizes = [table.width] if table.is_round else [table.width, table.depth]
    if _plausible(sizes):
        return
    numbers = [number for number, _ in sides]
    written = _units(sides)
    hint = ""
    for unit in _HINT_UNITS:
        if unit not in written and _plausible([_in_metres(n, unit) for n in numbers]):
            spelled = f"round:{numbers[0]}" if table.is_round else "x".join(numbers)
            hint = f"; did you mean {spelled}{unit}?"
            break
    what, side = (f"round {table.width:g} m", "diameter") if table.is_round else \
        (f"{table.width:g} x {table.depth:g} m", "each side")
    raise BadInput(f"{what} is not a dining table ({side} between "
                   f"{MIN_TABLE_SIDE_M:g} and {MAX_TABLE_SIDE_M:g} m){hint}", param="table")
