"""Pictures and terminal summaries of arrangements."""

from llm_grop.render.table import draw_arrangement

__all__ = ["draw_arrangement"]
