"""llm-grop: set a table the way people expect, from an underspecified request.

An implementation of LLM-GROP (Ding, Zhang, Paxton, Zhang, IROS 2023)::

    from llm_grop import arrange, Table
    result = arrange("a dinner plate, a dinner fork and a dinner knife", seed=0)
    for p in result.arrangement.placements:
        print(p.name, p.x, p.y)
"""

from llm_grop.api import arrange, make_llm
from llm_grop.arrangement.pipeline import ArrangementResult, ArrangeOptions
from llm_grop.errors import BadInput, Infeasible, LLMError, LLMGropError
from llm_grop.llm.base import BackendOptions, SamplingParams
from llm_grop.world import (
    Arrangement,
    Catalog,
    Configuration,
    Item,
    ObjectSpec,
    Placement,
    Relation,
    Table,
)
from llm_grop.world.serialize import arrangement_from_dict, arrangement_to_dict

__version__ = "0.1.0"

__all__ = [
    "Arrangement",
    "ArrangeOptions",
    "ArrangementResult",
    "BackendOptions",
    "BadInput",
    "Catalog",
    "Configuration",
    "Infeasible",
    "Item",
    "LLMError",
    "LLMGropError",
    "ObjectSpec",
    "Placement",
    "Relation",
    "SamplingParams",
    "Table",
    "arrange",
    "arrangement_from_dict",
    "arrangement_to_dict",
    "make_llm",
]
