"""Pictures of arrangements and runs, drawn from plain world records."""

from llm_grop.render.room import draw_run
from llm_grop.render.table import draw_arrangement

__all__ = ["draw_arrangement", "draw_run"]
