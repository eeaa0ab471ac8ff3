"""The world: objects, tables, relations and arrangements. Representation only."""

from llm_grop.world.arrangement import Arrangement, Configuration, Item, Placement
from llm_grop.world.catalog import Catalog, ObjectSpec
from llm_grop.world.llmlog import LLMSummary
from llm_grop.world.relation import RELATION_NAMES, Relation
from llm_grop.world.table import Table

__all__ = [
    "RELATION_NAMES",
    "Arrangement",
    "Catalog",
    "Configuration",
    "Item",
    "LLMSummary",
    "ObjectSpec",
    "Placement",
    "Relation",
    "Table",
]
