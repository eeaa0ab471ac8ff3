"""The published JSON documents by name, and their JSON Schemas: what ``llm-grop schema
NAME`` prints and ``docs/schema/`` holds."""

from __future__ import annotations

import json
import re
from typing import Any

from llm_grop.contract.models import ArrangementDoc, Doc, RunDoc, TrialRow
from llm_grop.contract.plan_doc import PlanJSON

#: The published documents, by the name ``llm-grop schema`` takes.
DOCUMENTS: dict[str, type[Doc]] = {
    "arrangement": ArrangementDoc,
    "run": RunDoc,
    "trial": TrialRow,
    "plan": PlanJSON,
}


def json_schema(name: str) -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of the document called ``name``."""
    schema = DOCUMENTS[name].model_json_schema(mode="validation")
    return {"$schema": "https://json-schema.org/draft/2020-12/schema",
            "$id": f"urn:llm-grop:schema:{name}", **_plain(schema)}


def _plain(node: Any) -> Any:
    """``node`` with its descriptions in plain text, not reStructuredText."""
    if isinstance(node, dict):
        return {k: _PLAIN.sub(r"`\1`", v) if k == "description" and isinstance(v, str)
                else _plain(v) for k, v in node.items()}
    if isinstance(node, list):
        return [_plain(v) for v in node]
    return node


#: A reference such as ``x`` or :class:`~llm_grop.contract.models.Doc` (kept: x, Doc).
_PLAIN = re.compile(r"(?::\w+:`~?(?:\w+\.)*)?`{1,2}([^`]+?)`{1,2}")


def schema_text(name: str) -> str:
    """:func:`json_schema` as the text committed under ``docs/schema/``."""
    return json.dumps(json_schema(name), indent=2, ensure_ascii=False) + "\n"
