"""The whole §III-A/§III-B pipeline against a real local OpenAI-compatible server."""

from __future__ import annotations

import pytest

from llm_grop import BackendOptions, Table, arrange
from llm_grop.arrangement.sampling import violations
from llm_grop.contract.serialize import arrangement_to_dict
from llm_grop.errors import Infeasible, LLMError
from llm_grop.files.jsonio import dumps
from scripted import PAPER_CONFLICT, PAPER_CONSISTENT, TASK1_GOOD, scripted

PAPER_REQUEST = "a fruit bowl, a butter knife, a dinner fork, a dinner knife and a water cup"


def _arrange(server, request: str, **kwargs):
    opts = BackendOptions(base_url=server.url, api_key="test", max_retries=0)
    return arrange(request, llm="openai", llm_options=opts, **kwargs)


def _strip_latency(data: dict) -> dict:
    for call in data["llm"]["log"]:
        call["latency_s"] = 0
    return data


def test_consistent_answer_gives_valid_configurations(chat_server) -> None:
    chat_server.reply = scripted([TASK1_GOOD])
    result = _arrange(chat_server, "a dinner plate, a dinner fork and a dinner knife", seed=3)
    rels = {(r.subject, r.relation, r.reference) for r in result.arrangement.relations}
    assert ("dinner fork", "to the left of", "dinner plate") in rels
    assert len(result.attempts) == 1 and not result.dropped
    assert len(result.configurations) == 25
    for config in result.configurations:
        assert violations(config, result.arrangement.relations, result.arrangement.table) == []
    pos = {p.name: p for p in result.arrangement.placements}
    assert pos["dinner fork"].x < pos["dinner plate"].x < pos["dinner knife"].x
    # 1 Template 1 prompt, 2 Template 2 prompts (center needs no distance), and the
    # plate's distance from the diner's edge.
    assert len(result.arrangement.llm.calls) == 4
    assert "edge of the table nearest the diner" in result.arrangement.llm.calls[-1].prompt
    assert result.gaps_m[("dinner fork", "to the left of", "dinner plate")] == pytest.approx(0.03)
    assert result.edge_gap_m == pytest.approx(0.03)
    for config, fid in zip(result.configurations, result.fidelity, strict=True):
        plate = config.by_name()["dinner plate"]
        assert plate.y - 0.135 + 0.3 == pytest.approx(0.03, abs=0.015)
        assert fid.max_gap_error_m <= 0.015


def test_same_seed_same_json(chat_server) -> None:
    chat_server.reply = scripted([TASK1_GOOD])
    a = _arrange(chat_server, "a dinner plate, a dinner fork and a dinner knife", seed=7)
    b = _arrange(chat_server, "a dinner plate, a dinner fork and a dinner knife", seed=7)
    c = _arrange(chat_server, "a dinner plate, a dinner fork and a dinner knife", seed=8)
    ja, jb, jc = (_strip_latency(arrangement_to_dict(r.arrangement)) for r in (a, b, c))
    assert dumps(ja) == dumps(jb)
    assert ja["objects"] != jc["objects"]


def test_paper_conflict_is_found_and_reprompted(chat_server) -> None:
    """With ``revisions=0`` a contradiction is answered as the paper does: Template 1 is
    asked again, blindly, with a new seed."""
    chat_server.reply = scripted([PAPER_CONFLICT, PAPER_CONSISTENT])
    result = _arrange(chat_server, PAPER_REQUEST, revisions=0)
    first = result.attempts[0]
    assert not first.consistent
    lines = PAPER_CONFLICT.splitlines()
    assert [r.line for r in first.conflict] == [lines[k][3:] for k in (1, 2, 4)]
    assert result.attempts[1].consistent and len(result.attempts) == 2
    assert result.arrangement.conflicts == (first.conflict,)
    seeds = [c.seed for c in result.arrangement.llm.calls[:2]]
    assert seeds[0] != seeds[1], "a re-prompt must resample"
    assert result.revisions == () and "cannot be used" not in str(chat_server.requests)


def test_attempts_run_out_keeps_largest_consistent_subset(chat_server) -> None:
    chat_server.reply = scripted([PAPER_CONFLICT])
    result = _arrange(chat_server, PAPER_REQUEST)
    assert len(result.attempts) == 3
    assert len(result.arrangement.relations) == 5
    assert len(result.dropped) == 1
    assert any(w.startswith("dropped to restore consistency") for w in result.arrangement.warnings)
    for config in result.configurations:
        assert violations(config, result.arrangement.relations, result.arrangement.table) == []


def test_left_out_object_gets_a_followup(chat_server) -> None:
    chat_server.reply = scripted(
        ["Place the dinner plate in the center of the table.\n"
         "Place the dinner fork to the left of the dinner plate."],
        followup="Place the dinner knife to the right of the dinner plate.")
    result = _arrange(chat_server, "a dinner plate, a dinner fork and a dinner knife")
    prompts = [c.prompt for c in result.arrangement.llm.calls]
    assert any("Where should a dinner knife be placed in relation to a dinner plate?" in p
               for p in prompts)
    rels = {(r.subject, r.relation, r.reference) for r in result.arrangement.relations}
    assert ("dinner knife", "to the right of", "dinner plate") in rels


def test_garbage_every_time_fails_after_bounded_attempts(chat_server) -> None:
    chat_server.reply = lambda body: "I like turtles."
    with pytest.raises(LLMError, match="no usable spatial relation in 3 attempt"):
        _arrange(chat_server, "a dinner plate, a dinner fork and a dinner knife")
    template1 = [r for r in chat_server.requests
                 if "What is a typical way" in r["messages"][-1]["content"]]
    assert len(template1) == 3


def test_table_too_small_is_infeasible(chat_server) -> None:
    chat_server.reply = scripted([TASK1_GOOD])
    with pytest.raises(Infeasible, match="too small"):
        _arrange(chat_server, "a dinner plate, a dinner fork and a dinner knife",
                 table=Table(0.2, 0.2))
