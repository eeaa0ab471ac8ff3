"""How llm-grop writes JSON: numbers rounded to 0.1 mm, UTF-8 text, atomic files."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from llm_grop.errors import BadInput

#: Decimal places kept for metres and radians in JSON (0.1 mm).
_DIGITS = 4


def rounded(value: float) -> float:
    """``value`` rounded to 0.1 mm / 0.1 mrad for JSON, without negative zero."""
    return round(float(value), _DIGITS) + 0.0  # + 0.0 turns -0.0 into 0.0


def dumps(data: Mapping[str, Any]) -> str:
    """JSON text as llm-grop writes it: UTF-8, two-space indent, trailing newline."""
    return json.dumps(data, indent=2, ensure_ascii=False) + "\n"


def write_json(path: str | Path, data: Mapping[str, Any]) -> None:
    """Write ``data`` atomically, so a failure never leaves half a file."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        tmp.write_text(dumps(data), encoding="utf-8")
        tmp.replace(path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise BadInput(f"{path}: cannot write ({exc.strerror})") from None
