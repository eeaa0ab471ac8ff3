"""Generalising a learned style to objects the examples do not show: the LLM's rules (a
real local OpenAI-compatible server answering as a model would), read with the one
vocabulary and kept only where the examples say nothing."""

from __future__ import annotations

import statistics
from pathlib import Path

import pytest

from learning_support import CATALOG, LEFT_HANDED, write_example
from llm_grop import BackendOptions, arrange, learn
from llm_grop.arrangement.generalising import generalise_prompt

RULES = ("Place the dinner fork to the left of the dinner plate.\n"  # the examples' own
         "Place the salad fork to the right of the dinner fork.\n"
         "Place the water cup above and to the left of the dinner plate.\n"
         "Place the water cup above the dinner plate.\n"  # a second rule for the cup
         "Place the bread to the left of the fruit bowl.\n"  # the bowl is nowhere
         "Place the salad fork to the left of the dinner plate.\n")


def _examples(tmp_path: Path) -> list[Path]:
    return [write_example(tmp_path / f"left{k}.json", LEFT_HANDED, k) for k in (1, 2)]


def _learn(server, tmp_path: Path):  # type: ignore[no-untyped-def]
    server.reply = lambda body: RULES
    opts = BackendOptions(base_url=server.url, api_key="t", max_retries=0)
    return learn(_examples(tmp_path), catalog=CATALOG, generalise=True, llm="openai",
                 llm_options=opts, seed=4)


def test_rules_place_only_what_the_examples_do_not_show(chat_server, tmp_path: Path
                                                        ) -> None:
    learned = _learn(chat_server, tmp_path)
    rules = [s for s in learned.sentences if s.sources[0].startswith("a rule by")]
    # Each rule takes the style's spacing: the median of the exact sentences' gaps.
    spacing = statistics.median(s.gap_cm for s in learned.sentences
                                if s.reference is not None and s not in rules)
    assert 2 <= spacing <= 3
    assert [s.sentence for s in rules] == [
        f"the salad fork {spacing:g} cm to the right of the dinner fork",
        f"the water cup {spacing:g} cm above and to the left of the dinner plate"]
    assert all(s.gap_cm == spacing and s.spread_cm is None
               and s.sources == ("a rule by gpt-4o-mini",) for s in rules)
    # The examples' own sentences are untouched: the fork stays on the right.
    assert any(s.sentence.startswith("the dinner fork ") and "to the right of" in s.sentence
               for s in learned.sentences)
    (warning,) = [w for w in learned.warnings if "rules not learned" in w]
    assert "'Place the dinner fork to the left of the dinner plate.' (the examples show " \
        "where it goes)" in warning
    assert "'Place the water cup above the dinner plate.' (a rule before it places that " \
        "object)" in warning
    assert "neither the examples nor a rule places" in warning
    (prompt,) = [b["messages"][-1]["content"] for b in chat_server.requests]
    assert prompt == generalise_prompt(
        [s for s in learned.sentences if s.reference is not None and s not in rules],
        [n for n in CATALOG.names() if n not in
         {"dinner plate", "dinner fork", "dinner knife", "mug"}])


def test_a_rule_sets_an_object_the_examples_never_showed(chat_server, tmp_path: Path
                                                         ) -> None:
    learned = _learn(chat_server, tmp_path)
    prefs = tmp_path / "prefs.yaml"
    prefs.write_text(learned.preference_file(), encoding="utf-8")
    chat_server.reply = lambda body: "About 3 centimeters."
    result = arrange("a dinner plate, a dinner fork and a water cup", llm="openai",
                     llm_options=BackendOptions(base_url=chat_server.url, api_key="t",
                                                max_retries=0),
                     preferences_file=str(prefs), seed=2)
    got = {r.key(): r for r in result.arrangement.relations}
    cup = got[("water cup", "above and to the left of", "dinner plate")]
    assert cup.source == "preference"
    rule = next(s for s in learned.sentences if s.subject == "water cup")
    assert rule.gap_cm is not None and cup.gap_m == pytest.approx(rule.gap_cm / 100)
    assert ("dinner fork", "to the right of", "dinner plate") in got


def test_without_a_capable_model_only_the_exact_sentences_are_learned(
        tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("LLM_GROP_PROBE_PORTS", "")
    monkeypatch.delenv("OPENAI_BASE_URL", raising=False)
    exact = learn(_examples(tmp_path), catalog=CATALOG)
    learned = learn(_examples(tmp_path), catalog=CATALOG, generalise=True)
    assert learned.sentences == exact.sentences
    (warning,) = learned.warnings
    assert warning.startswith("no capable model to generalise with")


def test_a_replayed_recording_generalises_the_same(chat_server, tmp_path: Path) -> None:
    record = tmp_path / "calls.jsonl"
    chat_server.reply = lambda body: RULES
    opts = BackendOptions(base_url=chat_server.url, api_key="t", max_retries=0)
    live = learn(_examples(tmp_path), catalog=CATALOG, generalise=True, llm="openai",
                 llm_options=opts, seed=4, record=record)
    again = learn(_examples(tmp_path), catalog=CATALOG, generalise=True, llm="replay",
                  llm_options=BackendOptions(replay_path=record), seed=4)
    assert [s.sentence for s in again.sentences] == [s.sentence for s in live.sentences]
