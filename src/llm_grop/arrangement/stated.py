"""Checking the relations a request states, before any arranging: they must hold together
(clingo) and their distances must fit on the table."""

from __future__ import annotations

from llm_grop.arrangement import consistency, preferences
from llm_grop.arrangement.preferences import contradiction
from llm_grop.errors import BadInput
from llm_grop.world.request import Request
from llm_grop.world.table import Table


def check_stated(request: Request, table: Table | None = None) -> None:
    """Raises :class:`BadInput` when ``request``'s relations (its ambiguous ones with
    them) cannot all hold, or, given the ``table``, a distance it states does not fit."""
    if request.relations or request.choices:
        conflict = consistency.choose(request.relations, request.choices).conflict
        if conflict:
            raise BadInput(f"request: {contradiction(conflict)}")
    if table is not None:
        everything = [*request.relations,
                      *(r for c in request.choices for option in c.options for r in option)]
        preferences.stated_gaps(everything, table)


__all__ = ["check_stated"]
