"""The target table and its frame.

Table frame (the contract's): origin at the centre of the table top, +x to the
diner's right, +y away from the diner. The diner sits at the -y edge.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from llm_grop.errors import BadInput

DEFAULT_TABLE_SIZE_M = (0.9, 0.6)


@dataclass(frozen=True)
class Table:
    """A rectangular table top: ``width`` along x and ``depth`` along y, in metres."""

    width: float = DEFAULT_TABLE_SIZE_M[0]
    depth: float = DEFAULT_TABLE_SIZE_M[1]
    shape: str = "rectangle"

    def __post_init__(self) -> None:
        if not (self.width > 0 and self.depth > 0):
            raise BadInput(f"table: size must be positive, got {self.width} x {self.depth} m")

    @property
    def size(self) -> tuple[float, float]:
        """``(width, depth)`` in metres."""
        return (self.width, self.depth)

    @classmethod
    def parse(cls, text: str) -> Table:
        """A table from ``"WxD"`` in metres, e.g. ``"0.9x0.6"``."""
        m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*[xX×*]\s*([0-9]*\.?[0-9]+)\s*", text)
        if not m:
            raise BadInput(f"--table: expected WxD in metres such as 0.9x0.6, got {text!r}")
        return cls(float(m.group(1)), float(m.group(2)))
