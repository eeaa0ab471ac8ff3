"""The feedback loop (issue 41): logical and geometric failures explained back to the LLM,
against a real local OpenAI-compatible server answering as a model would."""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from cli_support import openai_flags
from llm_grop import BackendOptions, Table, arrange, run
from llm_grop.arrangement.revision import BUNDLED_MODEL, DEFAULT_ROUNDS, rounds_for
from llm_grop.arrangement.sampling import violations
from llm_grop.cli import main
from llm_grop.contract.run_json import run_to_dict
from llm_grop.contract.schemas import json_schema
from llm_grop.contract.serialize import arrangement_to_dict
from llm_grop.errors import Infeasible
from llm_grop.seeds import int_seed
from scripted import PAPER_CONFLICT, PAPER_CONSISTENT

PAPER_REQUEST = "a fruit bowl, a butter knife, a dinner fork, a dinner knife and a water cup"
MUG_REQUEST = "a dinner plate and a mug"
#: Another contradiction: the fork both left and right of the bowl.
OTHER_CONFLICT = (
    "Place the fruit bowl in the center of the table.\n"
    "Place the dinner fork to the left of the fruit bowl.\n"
    "Place the dinner fork to the right of the fruit bowl.\n"
    "Place the dinner knife to the right of the fruit bowl.\n"
    "Place the butter knife to the right of the dinner knife.\n"
    "Place the water cup above the fruit bowl."
)
MUG_ABOVE = ("Place the dinner plate in the center of the table.\n"
             "Place the mug above the dinner plate.")
MUG_RIGHT = ("Place the dinner plate in the center of the table.\n"
             "Place the mug to the right of the dinner plate.")
#: 0.45 m wide, 0.3 m deep: the plate (0.27 m) and the mug (0.09 m) fit side by side, not
#: one above the other.
SMALL = Table.parse("0.45x0.3")


def is_revision(prompt: str) -> bool:
    return "That answer cannot be used:" in prompt


def answering(template1: Sequence[str], revisions: Sequence[str], followup: str = ""
              ) -> Callable[[dict[str, Any]], str]:
    """Template 1 prompts get ``template1`` in turn, revision prompts ``revisions`` in turn
    (the last of each repeats), follow-ups ``followup``; distances are 3 cm."""
    n = {"t1": 0, "rev": 0}

    def reply(body: dict[str, Any]) -> str:
        prompt = body["messages"][-1]["content"]
        if "how many centimeters" in prompt.lower():
            return "About 3 centimeters."
        if "where should" in prompt.lower():
            return followup
        key, answers = ("rev", revisions) if is_revision(prompt) else ("t1", template1)
        k = min(n[key], len(answers) - 1)
        n[key] += 1
        return answers[k]

    return reply


def _arrange(server, request: str, **kwargs):  # type: ignore[no-untyped-def]
    """``arrange`` against ``server`` with the loop on (2 rounds) unless said otherwise."""
    opts = BackendOptions(base_url=server.url, api_key="test", max_retries=0)
    return arrange(request, llm="openai", llm_options=opts, **{"revisions": 2} | kwargs)


def _prompts(server) -> list[str]:  # type: ignore[no-untyped-def]
    return [b["messages"][-1]["content"] for b in server.requests]


def test_a_contradiction_is_explained_and_the_revision_used(chat_server) -> None:
    chat_server.reply = answering([PAPER_CONFLICT], [PAPER_CONSISTENT])
    result = _arrange(chat_server, PAPER_REQUEST, seed=4)
    assert len(result.attempts) == 1, "no blind re-prompt: the revision was used"
    (rev,) = result.revisions
    assert rev.outcome == "accepted" and rev.failure.kind == "logical"
    # The model is told what clashed, in its own words.
    for line in ("butter knife above and to the right of fruit bowl",
                 "dinner fork to the left of butter knife",
                 "fruit bowl to the right of dinner fork"):
        assert line in rev.failure.reason and line in rev.asked
    asked = [p for p in _prompts(chat_server) if is_revision(p)]
    assert asked == [rev.asked]
    assert "Place the butter knife above and to the right of the fruit bowl." in rev.asked
    revision_call = next(c for c in result.arrangement.llm.calls if is_revision(c.prompt))
    assert revision_call.seed == int_seed(4, "llm.revision", 1)
    a = result.arrangement
    from_revision = {r.key() for r in a.relations if r.revision == 1}
    assert {r.source for r in a.relations if r.revision == 1} == {"revision"}
    assert from_revision == {r.key() for r in rev.added} and from_revision
    proposed = result.attempts[0].relations
    said = {r.key() for r in proposed} | {r.converse().key() for r in proposed if r.reference}
    assert {r.key() for r in a.relations if r.revision is None} <= said
    assert {r.source for r in a.relations if r.revision is None} == {"llm"}
    for config in result.configurations:
        assert violations(config, a.relations, a.table) == []
    doc = arrangement_to_dict(a)
    jsonschema.validate(doc, json_schema("arrangement"))
    (written,) = doc["revisions"]
    assert written["outcome"] == "accepted" and written["failure"]["kind"] == "logical"
    assert [r["line"] for r in written["failure"]["relations"]] == \
        [r.line for r in rev.failure.relations]
    assert {r.get("revision") for r in doc["relations"]} == {None, 1}


def test_an_object_a_revision_leaves_out_gets_a_follow_up(chat_server) -> None:
    left_out = "\n".join(line for line in PAPER_CONSISTENT.splitlines() if "water cup" not in line)
    chat_server.reply = answering([PAPER_CONFLICT], [left_out],
                                  followup="Place the water cup above the fruit bowl.")
    result = _arrange(chat_server, PAPER_REQUEST, seed=2)
    (rev,) = result.revisions
    assert rev.outcome == "accepted"
    cup = [r for r in result.arrangement.relations if "water cup" in (r.subject, r.reference)]
    assert [(r.key(), r.revision) for r in cup] == [(("water cup", "above", "fruit bowl"), 1)]
    asked = [c for c in result.arrangement.llm.calls if "Where should" in c.prompt]
    assert [c.seed for c in asked] == [int_seed(2, "llm.revision", 1, 1)]


def test_a_revision_that_clashes_again_is_explained_in_turn(chat_server) -> None:
    chat_server.reply = answering([PAPER_CONFLICT], [OTHER_CONFLICT, PAPER_CONSISTENT])
    result = _arrange(chat_server, PAPER_REQUEST)
    first, second = result.revisions
    assert first.outcome == "refused" and "contradict" in first.note
    assert second.outcome == "accepted"
    assert "'Place the dinner fork to the right of the fruit bowl.'" in second.failure.reason \
        or "dinner fork to the right of the fruit bowl" in second.failure.reason
    assert "Place the dinner fork to the right of the fruit bowl." in second.asked
    assert len(result.attempts) == 1


@pytest.mark.parametrize(("revision", "why"), [
    ("I am not sure how to arrange these.", "no usable relation"),
    (PAPER_CONFLICT, "repeats the failed relations"),
])
def test_an_unusable_revision_keeps_the_original_failure(chat_server, revision: str,
                                                         why: str) -> None:
    """Nothing is made worse: one warning, then the paper's blind re-prompt goes on."""
    chat_server.reply = answering([PAPER_CONFLICT, PAPER_CONSISTENT], [revision])
    result = _arrange(chat_server, PAPER_REQUEST)
    (rev,) = result.revisions
    assert rev.outcome == "refused" and why in rev.note
    assert len(result.attempts) == 2 and result.attempts[1].consistent
    assert all(r.revision is None for r in result.arrangement.relations)
    warned = [w for w in result.arrangement.warnings if w.startswith("revision 1 refused")]
    assert len(warned) == 1 and why in warned[0]
    assert len([p for p in _prompts(chat_server) if is_revision(p)]) == 1


def test_revisions_are_bounded(chat_server) -> None:
    chat_server.reply = answering([PAPER_CONFLICT], [OTHER_CONFLICT])
    result = _arrange(chat_server, PAPER_REQUEST, revisions=1)
    assert len(result.revisions) == 1
    assert len([p for p in _prompts(chat_server) if is_revision(p)]) == 1
    assert len(result.attempts) == 3  # then the paper's re-prompts, then the largest subset


def test_relations_no_placement_keeps_are_revised(chat_server) -> None:
    chat_server.reply = answering([MUG_ABOVE], [MUG_RIGHT])
    result = _arrange(chat_server, MUG_REQUEST, table=SMALL)
    (rev,) = result.revisions
    assert rev.outcome == "accepted" and rev.failure.kind == "geometric"
    assert rev.failure.objects == ("mug",)
    assert "the 0.45 x 0.3 m table" in rev.failure.reason and "mug" in rev.failure.reason
    assert [r.key() for r in rev.failure.relations] == [("mug", "above", "dinner plate")]
    rels = {r.key(): r for r in result.arrangement.relations}
    assert rels[("mug", "to the right of", "dinner plate")].revision == 1
    assert ("mug", "above", "dinner plate") not in rels
    pos = {p.name: p for p in result.arrangement.placements}
    assert pos["mug"].x > pos["dinner plate"].x
    # The plate's gap and distance from the diner's edge were asked once, not again.
    distance_questions = [p for p in _prompts(chat_server) if "centimeters" in p.lower()]
    assert len(distance_questions) == len(set(distance_questions))


def test_without_rounds_left_the_geometric_failure_stands(chat_server) -> None:
    chat_server.reply = answering([MUG_ABOVE], [MUG_ABOVE])
    with pytest.raises(Infeasible, match="mug leaves the 0.45 x 0.3 m table"):
        _arrange(chat_server, MUG_REQUEST, table=SMALL)
    assert len([p for p in _prompts(chat_server) if is_revision(p)]) == 1  # then a repeat
    chat_server.requests.clear()
    with pytest.raises(Infeasible, match="mug leaves"):
        _arrange(chat_server, MUG_REQUEST, table=SMALL, revisions=0)
    assert not [p for p in _prompts(chat_server) if is_revision(p)]


def test_a_recording_made_without_the_loop_still_replays(chat_server, tmp_path: Path) -> None:
    """A replay with no answer to a revision prompt refuses the round and goes on as the
    recording did."""
    chat_server.reply = answering([PAPER_CONFLICT, PAPER_CONSISTENT], [PAPER_CONSISTENT])
    record = tmp_path / "calls.jsonl"
    made = _arrange(chat_server, PAPER_REQUEST, revisions=0, record=record)
    again = arrange(PAPER_REQUEST, llm="replay", revisions=2,
                    llm_options=BackendOptions(replay_path=record))
    (rev,) = again.revisions
    assert rev.outcome == "refused" and "no answer" in rev.note
    assert again.arrangement.relations == made.arrangement.relations
    assert again.arrangement.placements == made.arrangement.placements


def test_revisions_replay_from_their_recording(chat_server, tmp_path: Path) -> None:
    chat_server.reply = answering([PAPER_CONFLICT], [PAPER_CONSISTENT])
    record = tmp_path / "calls.jsonl"
    made = _arrange(chat_server, PAPER_REQUEST, record=record)
    again = arrange(PAPER_REQUEST, llm="replay", revisions=2,
                    llm_options=BackendOptions(replay_path=record))
    assert [r.outcome for r in again.revisions] == ["accepted"]
    assert again.arrangement.relations == made.arrangement.relations


def test_the_run_json_records_the_revisions(chat_server) -> None:
    chat_server.reply = answering([MUG_ABOVE], [MUG_RIGHT])
    opts = BackendOptions(base_url=chat_server.url, api_key="t", max_retries=0)
    result = run(MUG_REQUEST, seed=1, chairs=1, llm="openai", llm_options=opts,
                 table="0.45x0.3", revisions=2)
    doc = run_to_dict(result)
    jsonschema.validate(doc, json_schema("run"))
    (rev,) = doc["planned"]["revisions"]
    assert rev["failure"]["kind"] == "geometric" and rev["outcome"] == "accepted"
    assert [r["relation"] for r in rev["added"]] == ["to the right of"]
    assert "revisions" not in doc["final"]
    assert json.dumps(doc)  # plain JSON


def test_a_diners_setting_that_does_not_fit_their_place_is_revised(chat_server) -> None:
    """Two diners face each other across a 0.9 x 0.6 m top: each place is 0.3 m deep, so
    the mug fits beside the plate, not above it; the revised setting is every diner's."""
    chat_server.reply = answering([MUG_ABOVE], [MUG_RIGHT])
    result = _arrange(chat_server, "set the table for two with a dinner plate and a mug",
                      table=Table.parse("0.9x0.6"))
    (rev,) = result.revisions
    assert rev.outcome == "accepted" and rev.failure.kind == "geometric"
    assert rev.failure.objects == ("mug",)  # in the first diner's names
    keys = {r.key() for r in result.arrangement.relations}
    assert {("mug", "to the right of", "dinner plate"),
            ("mug 2", "to the right of", "dinner plate 2")} <= keys
    assert not any(r.relation == "above" for r in result.arrangement.relations)


def test_the_console_shows_each_round(chat_server, capsys) -> None:  # type: ignore[no-untyped-def]
    chat_server.reply = answering([MUG_ABOVE], [MUG_RIGHT])
    code = main(["arrange", MUG_REQUEST, *openai_flags(chat_server), "--table", "0.45x0.3",
                 "--revisions", "2"])
    out = capsys.readouterr().out
    assert code == 0
    assert "Revision 1 (geometric): accepted, 1 relation(s) added, 1 dropped: Place the mug " \
        "to the right of the dinner plate." in " ".join(out.split())
    assert "told: the mug cannot be placed" in " ".join(out.split())
    assert "revision 1" in out and "llm, revision" not in out


def _default(server, request: str, **kwargs):  # type: ignore[no-untyped-def]
    """``arrange`` against ``server`` with ``revisions`` left to its default."""
    opts = BackendOptions(base_url=server.url, api_key="test", max_retries=0, **kwargs)
    return arrange(request, llm="openai", llm_options=opts)


def test_by_default_a_capable_model_is_told_what_clashed(chat_server) -> None:
    chat_server.reply = answering([PAPER_CONFLICT], [PAPER_CONSISTENT])
    result = _default(chat_server, PAPER_REQUEST)
    assert [r.outcome for r in result.revisions] == ["accepted"]


def test_by_default_the_bundled_model_is_asked_again_blindly(chat_server, tmp_path: Path
                                                            ) -> None:
    """The bundled SmolLM2-135M's revisions measured worse than a blind re-prompt: without
    ``revisions`` its runs, live or replayed, keep the paper's way."""
    chat_server.reply = answering([PAPER_CONFLICT, PAPER_CONSISTENT], [PAPER_CONSISTENT])
    record = tmp_path / "calls.jsonl"
    opts = BackendOptions(base_url=chat_server.url, api_key="test", max_retries=0,
                          model=BUNDLED_MODEL)
    live = arrange(PAPER_REQUEST, llm="openai", llm_options=opts, record=record)
    assert live.revisions == () and not any(is_revision(p) for p in _prompts(chat_server))
    again = arrange(PAPER_REQUEST, llm="replay", llm_options=BackendOptions(replay_path=record))
    assert again.revisions == ()
    assert again.arrangement.relations == live.arrangement.relations
    assert again.arrangement.placements == live.arrangement.placements


@pytest.mark.parametrize(("revisions", "model", "rounds"), [
    (None, BUNDLED_MODEL, 0), (None, "qwen2.5:7b", DEFAULT_ROUNDS), (1, BUNDLED_MODEL, 1),
    (0, "qwen2.5:7b", 0)])
def test_the_rounds_a_run_may_spend(revisions: int | None, model: str, rounds: int) -> None:
    assert rounds_for(revisions, model) == rounds


def test_relations_the_user_stated_are_not_sent_for_revision(chat_server) -> None:
    """Preferences that leave the mug no room on the small table are the user's: the
    sampler's failure stands and the LLM is not asked to revise them (only for the gaps
    the preferences leave open)."""
    prefs = ("the dinner plate in the center of the table",
             "the mug above the dinner plate")
    with pytest.raises(Infeasible, match="no feasible arrangement"):
        _arrange(chat_server, MUG_REQUEST, table=SMALL, preferences=prefs)
    assert not any(is_revision(p) for p in _prompts(chat_server))
