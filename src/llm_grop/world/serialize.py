"""The one place where world records turn into the contract's JSON and back."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from llm_grop.errors import BadInput
from llm_grop.world.arrangement import Arrangement, Placement
from llm_grop.world.llmlog import LLMCallRecord, LLMSummary
from llm_grop.world.relation import Relation
from llm_grop.world.table import Table

#: Decimal places kept for metres and radians in JSON (0.1 mm).
_DIGITS = 4


def rounded(value: float) -> float:
    """``value`` rounded to 0.1 mm / 0.1 mrad for JSON, without negative zero."""
    return round(float(value), _DIGITS) + 0.0  # + 0.0 turns -0.0 into 0.0


def relation_to_dict(rel: Relation) -> dict[str, Any]:
    """``{"subject", "relation", "reference"}`` (reference ``null`` for ``center``)."""
    return {"subject": rel.subject, "relation": rel.relation, "reference": rel.reference}


def placement_to_dict(p: Placement) -> dict[str, Any]:
    """A contract ``objects[]`` entry."""
    return {
        "name": p.name, "x": rounded(p.x), "y": rounded(p.y), "yaw": rounded(p.yaw),
        "shape": p.shape,
        "size": [rounded(p.size[0]), rounded(p.size[1])], "on": p.on,
        "kind": p.kind or p.name, "height": rounded(p.height),
    }


def call_to_dict(c: LLMCallRecord) -> dict[str, Any]:
    """One logged LLM call."""
    return {
        "prompt": c.prompt, "response": c.response, "latency_s": round(c.latency_s, 4),
        "prompt_tokens": c.prompt_tokens, "completion_tokens": c.completion_tokens,
        "seed": c.seed,
    }


def arrangement_to_dict(a: Arrangement) -> dict[str, Any]:
    """The contract's arrangement JSON as a dict."""
    out: dict[str, Any] = {
        "request": a.request,
        "table": {"shape": a.table.shape, "size": [rounded(a.table.width), rounded(a.table.depth)]},
        "objects": [placement_to_dict(p) for p in a.placements],
        "relations": [relation_to_dict(r) for r in a.relations],
    }
    if a.llm is not None:
        out["llm"] = {"backend": a.llm.backend, "model": a.llm.model, "calls": len(a.llm.calls),
                      "log": [call_to_dict(c) for c in a.llm.calls]}
    out["warnings"] = list(a.warnings)
    out["conflicts"] = [[relation_to_dict(r) | {"line": r.line} for r in core]
                        for core in a.conflicts]
    return out


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


def arrangement_from_dict(data: Mapping[str, Any], where: str = "arrangement") -> Arrangement:
    """An :class:`Arrangement` from the contract's JSON (as written by any system)."""
    try:
        table = Table(*map(float, data["table"]["size"]), data["table"].get("shape", "rectangle"))
        placements = []
        for i, o in enumerate(data["objects"]):
            shape = o.get("shape", "box")
            if shape not in ("circle", "box"):
                raise BadInput(f"{where}: objects[{i}].shape must be 'circle' or 'box'")
            x, y, yaw = float(o["x"]), float(o["y"]), float(o.get("yaw", 0.0))
            if not all(map(math.isfinite, (x, y, yaw))):
                raise BadInput(f"{where}: objects[{i}]: x, y and yaw must be finite numbers")
            placements.append(Placement(
                name=str(o["name"]), x=x, y=y, yaw=yaw, shape=shape,
                size=(float(o["size"][0]), float(o["size"][1])), on=o.get("on"),
                kind=str(o.get("kind", o["name"])), height=float(o.get("height", 0.0))))
        relations = tuple(
            Relation(str(r["subject"]), str(r["relation"]), r.get("reference"))
            for r in data.get("relations", []))
        llm = None
        if isinstance(data.get("llm"), Mapping):
            llm = LLMSummary(str(data["llm"].get("backend", "")), str(data["llm"].get("model", "")))
    except BadInput:
        raise
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise BadInput(f"{where}: not a valid arrangement JSON ({type(exc).__name__}: {exc})"
                       ) from None
    return Arrangement(str(data.get("request", "")), table, tuple(placements), relations, llm,
                       tuple(data.get("warnings", ())))
