"""LLM-GROP."""
