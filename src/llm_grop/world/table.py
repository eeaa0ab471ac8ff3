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
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, get_args

from llm_grop.errors import BadInput
from llm_grop.world.seat import Seat

DEFAULT_TABLE_SIZE_M = (0.9, 0.6)

TableShape = Literal["rectangle", "circle"]
#: The shapes a table top may have, as the contract names them.
TABLE_SHAPES: tuple[str, ...] = get_args(TableShape)

_NUMBER = r"\s*([0-9]*\.?[0-9]+)\s*"
_RECTANGLE_TEXT = re.compile(_NUMBER + r"[xX×*]" + _NUMBER)
_ROUND_TEXT = re.compile(r"\s*round\s*:" + _NUMBER, re.IGNORECASE)
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
        if not (self.width > 0 and self.depth > 0):
            raise BadInput(f"table: size must be positive, got {self.width} x {self.depth} m")
        if self.shape not in TABLE_SHAPES:
            raise BadInput(f"table: shape must be one of {', '.join(TABLE_SHAPES)}, "
                           f"got {self.shape!r}")
        if self.is_round and not math.isclose(self.width, self.depth, rel_tol=0.0,
                                              abs_tol=_ROUND_TOL_M):
            raise BadInput(f"table: a round table has one size, its diameter, but was given "
                           f"{self.width:g} x {self.depth:g} m; use [d, d]")
        for k, seat in enumerate(self.diners):
            if self._inside(seat.x, seat.y):
                raise BadInput(f"table: diner {k}'s seat at ({seat.x:+.2f}, {seat.y:+.2f}) m "
                               f"lies inside the {self.label}; a seat goes at or beyond its edge")

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
        """A table from ``"WxD"`` in metres (``"0.9x0.6"``) or ``"round:D"``, a round top
        of diameter ``D`` metres (``"round:1.2"``). Raises :class:`BadInput` otherwise."""
        if text.strip().lower().startswith("round"):
            m = _ROUND_TEXT.fullmatch(text)
            if not m:
                raise BadInput(f"--table: a round table has one size, its diameter in metres: "
                               f"round:D such as round:1.2, got {text!r}")
            return _flagged(cls.circle, float(m.group(1)))
        m = _RECTANGLE_TEXT.fullmatch(text)
        if not m:
            raise BadInput(f"--table: expected WxD in metres such as 0.9x0.6, or round:D such "
                           f"as round:1.2, got {text!r}")
        return _flagged(cls, float(m.group(1)), float(m.group(2)))


def _flagged(make: Callable[..., Table], *size: float) -> Table:
    """``make(*size)``, its :class:`BadInput` naming the ``--table`` flag."""
    try:
        return make(*size)
    except BadInput as exc:
        raise BadInput(f"--{exc}") from None
