"""The feedback loop before planning fails: relations that put an object out of the robot's
reach in every configuration are explained to the LLM (a real local OpenAI-compatible
server answering as a model would; the planner's own reach)."""

from __future__ import annotations

from typing import Any

import pytest

from llm_grop import BackendOptions, plan
from llm_grop.errors import Infeasible

REQUEST = "a dinner plate, a dinner fork, a dinner knife and a mug"
#: The mug beyond the knife, far into a wide table whose sides two chairs block.
FIRST = ("Place the dinner plate in the center of the table.\n"
         "Place the dinner fork to the left of the dinner plate.\n"
         "Place the dinner knife to the right of the dinner plate.\n"
         "Place the mug above and to the right of the dinner knife.")
REVISED = ("Place the dinner plate in the center of the table.\n"
           "Place the dinner fork to the left of the dinner plate.\n"
           "Place the dinner knife to the right of the dinner plate.\n"
           "Place the mug to the right of the dinner knife.")


def reply(body: dict[str, Any]) -> str:
    prompt = body["messages"][-1]["content"]
    if "how many centimeters" in prompt.lower():
        return "About 3 centimeters."
    return REVISED if "That answer cannot be used:" in prompt else FIRST


def _plan(server, revisions: int):  # type: ignore[no-untyped-def]
    server.reply = reply
    return plan(REQUEST, llm="openai", table="2.0x1.4", chairs=2, seed=0,
                feasibility="default", revisions=revisions,
                llm_options=BackendOptions(base_url=server.url, api_key="t", max_retries=0))


def test_without_the_loop_planning_fails_out_of_reach(chat_server) -> None:
    with pytest.raises(Infeasible, match="no standing position can reach 'mug'"):
        _plan(chat_server, 0)


def test_the_llm_is_told_the_mug_is_out_of_reach_and_its_revision_planned(chat_server
                                                                          ) -> None:
    planned = _plan(chat_server, 2)
    (rev,) = planned.planned.arrangement.revisions
    assert (rev.failure.kind, rev.outcome, rev.failure.objects) == ("physical", "accepted",
                                                                   ("mug",))
    assert "within its arm's reach of it (0.85 m)" in rev.failure.reason
    assert "Place the mug above and to the right of the dinner knife." in rev.asked
    mug = {r.key(): r for r in planned.planned.arrangement.relations}[
        ("mug", "to the right of", "dinner knife")]
    assert (mug.source, mug.revision) == ("revision", 1)
    assert len(planned.planned.plan.order) == 4
