"""Minimal valid bench trial rows (the contract's TrialRow) for summary and plot tests."""

from __future__ import annotations

from typing import Any


def trial_row(method: str, task: int, rating: int, execution: float | None,
              planning: float | None = 0.01, success: bool | None = None,
              trial: int = 0) -> dict[str, Any]:
    """A row of ``method`` on ``task``: rated ``rating``, executed in ``execution`` seconds
    (``None``: no plan, an infeasible trial)."""
    ok = execution is not None
    return {
        "method": method, "task": task, "seed": 7 + trial, "request": "a mug",
        "success": ok if success is None else success, "execution_time_s": execution,
        "planning_time_s": planning if ok else None, "failures": 0, "unplaced": [],
        "steps": [], "final": {"table": {"size": [0.9, 0.6]}, "objects": []},
        "status": "ok" if ok else "infeasible", "trial": trial, "retries": 0,
        "llm_calls": 0, "llm_prompt_tokens": 0, "llm_completion_tokens": 0,
        "llm_time_s": 0.0, "rating": rating,
        "rating_explanation": {"score": rating, "summary": f"{rating}/5", "checks": []},
    }
