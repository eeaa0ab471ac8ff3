"""Example settings for the learning tests, made by the real pipeline: a style written as
preferences, arranged with a fixed seed, written as the contract's arrangement JSON."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from llm_grop import BackendOptions, arrange
from llm_grop.arrangement.pipeline import ArrangeOptions
from llm_grop.contract.serialize import arrangement_to_dict
from llm_grop.world.catalog import Catalog
from llm_grop.world.table import Table

CATALOG = Catalog.load(use_env=False)
#: A replay recording with no call in it: the styles state every relation and distance, so
#: no LLM is asked, and a call would fail the test.
NO_CALLS = Path(__file__).parent / "arrangement" / "no_calls.jsonl"
SETTING = "a dinner plate, a dinner fork, a dinner knife and a mug"

#: A left-handed diner: fork on the right, knife on the left, mug on the upper left.
LEFT_HANDED = (
    "the dinner plate 4 cm from the diner's edge of the table",
    "the dinner fork 3 cm to the right of the dinner plate",
    "the dinner knife 2 cm to the left of the dinner plate",
    "the mug 3 cm above and to the left of the dinner plate",
)
#: The usual setting (as benchmarks/data/preferences.yaml has it).
USUAL = (
    "the dinner plate 3 cm from the diner's edge of the table",
    "the dinner fork 2 cm to the left of the dinner plate",
    "the dinner knife 2 cm to the right of the dinner plate",
    "the mug 3 cm above and to the right of the dinner plate",
)
#: A mug with its lid, on its mat, beside a plate.
STACKED = (
    "the dinner plate 3 cm from the diner's edge of the table",
    "the mug mat 3 cm above and to the right of the dinner plate",
    "the mug on top of the mug mat",
    "the mug lid on top of the mug",
)


def arranged(style: tuple[str, ...], seed: int, request: str = SETTING,
             table: Table | None = None) -> dict[str, Any]:
    """The arrangement JSON of ``request`` set in ``style`` with ``seed``."""
    result = arrange(request, llm="replay", llm_options=BackendOptions(replay_path=str(NO_CALLS)),
                     seed=seed, catalog=CATALOG, options=ArrangeOptions(preference_pool=style),
                     **({"table": table} if table is not None else {}))
    return arrangement_to_dict(result.arrangement)


def write_example(path: Path, style: tuple[str, ...], seed: int, request: str = SETTING,
                  table: Table | None = None) -> Path:
    """``path`` holding the arrangement JSON of :func:`arranged`."""
    path.write_text(json.dumps(arranged(style, seed, request, table)), encoding="utf-8")
    return path
