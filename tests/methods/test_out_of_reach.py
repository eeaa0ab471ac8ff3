"""The feedback loop before planning fails: relations that put an object out of the robot's
reach in every configuration are explained to the LLM (a real local OpenAI-compatible
server answering as a model would; the planner's own reach)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import pytest

from llm_grop import BackendOptions, arrange, plan
from llm_grop.arrangement.options import ArrangeOptions
from llm_grop.errors import Infeasible
from llm_grop.world.arrangement import Placement

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


def _second_diners_far_mug(placements: Sequence[Placement]) -> tuple[str, str] | None:
    """A robot that reaches the second diner's mug only within 0.2 m of the 1.2 m deep
    table's edge (table frame: the edge is 0.6 m from the centre)."""
    for p in placements:
        if p.name == "mug 2" and 0.6 - abs(p.y) > 0.2:
            return p.name, f"it is {0.6 - abs(p.y):.2f} m from the table's edge"
    return None


@pytest.mark.parametrize("revisions", [0, 2])
def test_with_several_diners_the_setting_out_of_reach_is_revised(chat_server, revisions: int
                                                                 ) -> None:
    chat_server.reply = reply
    result = arrange("set the table for two with " + REQUEST,
                     llm="openai", table="1.6x1.2", seed=0, revisions=revisions,
                     options=ArrangeOptions(reach=_second_diners_far_mug),
                     llm_options=BackendOptions(base_url=chat_server.url, api_key="t",
                                                max_retries=0))
    a = result.arrangement
    mugs = {r.subject: r for r in a.relations if r.subject.startswith("mug")}
    if not revisions:
        assert a.revisions == ()
        assert mugs["mug 2"].relation == "above and to the right of"
        return
    # Told in the first diner's names, the one distinct setting is revised for both.
    (rev,) = a.revisions
    assert (rev.failure.kind, rev.outcome, rev.failure.objects) == ("physical", "accepted",
                                                                   ("mug",))
    assert "m from the table's edge" in rev.failure.reason
    assert {(r.relation, r.reference, r.source) for r in mugs.values()} == {
        ("to the right of", "dinner knife", "revision"),
        ("to the right of", "dinner knife 2", "revision")}
    (mug2,) = [p for p in a.placements if p.name == "mug 2"]
    assert 0.6 - abs(mug2.y) <= 0.2
