"""Scripted answers for the local chat server: Template 1, follow-ups and Template 2."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

TASK1_GOOD = (
    "1. Place the dinner plate in the center of the table.\n"
    "2. Place the dinner fork to the left of the dinner plate.\n"
    "3. Place the dinner knife to the right of the dinner plate."
)

#: The paper's §III-A example: lines 2, 3 and 5 conflict.
PAPER_CONFLICT = (
    "1. Place fruit bowl in the center of table.\n"
    "2. Place butter knife above and to the right of fruit bowl.\n"
    "3. Place dinner fork to the left of butter knife.\n"
    "4. Place dinner knife to the right of butter knife.\n"
    "5. Place fruit bowl to the right of dinner fork.\n"
    "6. Place water cup below and to the left of dinner knife."
)

PAPER_CONSISTENT = (
    "Place the fruit bowl in the center of the table.\n"
    "Place the dinner fork to the left of the fruit bowl.\n"
    "Place the dinner knife to the right of the fruit bowl.\n"
    "Place the butter knife to the right of the dinner knife.\n"
    "Place the water cup above and to the right of the fruit bowl."
)


def scripted(answers: Sequence[str], distance: str = "About 3 centimeters.",
             followup: str = "", reading: str = "diners: 1"
             ) -> Callable[[dict[str, Any]], str]:
    """A reply function: Template 1 prompts get ``answers`` in turn (the last repeats);
    the question that reads a whole request gets ``reading``."""
    state = {"n": 0}

    def reply(body: dict[str, Any]) -> str:
        prompt = body["messages"][-1]["content"]
        if "A person asked:" in prompt:
            return reading
        if "how many centimeters" in prompt.lower():
            return distance
        if "where should" in prompt.lower():
            return followup
        k = min(state["n"], len(answers) - 1)
        state["n"] += 1
        return answers[k]

    return reply
