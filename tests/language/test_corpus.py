"""The phrasing corpus (``phrasings.yaml``: requests as people write them, each with the
reading a person means), read three ways:

(a) the fast path reads a phrasing exactly, or leaves it to the LLM; it never reads one
    wrongly, and it reads alone exactly those marked ``fast``;
(b) a local OpenAI-compatible server answers each phrasing with its expected reading: the
    LLM path carries a good answer through unchanged;
(c) the embedded model's readings are a report, not an assertion: ``benchmarks/phrasings.py``.

Every refusal of the corpus is a one-line error (exit 2 from the command line), and a
property test shows that a request the fast path reads gives the same reading through the
LLM path given that reading as its answer.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from corpus import as_answer, load_cases, load_refusals, same
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from llm_grop import BackendOptions, make_llm
from llm_grop.api import understand
from llm_grop.cli import main
from llm_grop.errors import BadInput
from llm_grop.language.llm_reading import answer_of
from llm_grop.language.request import read_request
from llm_grop.language.understanding import read_with_llm
from llm_grop.llm.base import CallLog
from llm_grop.llm.openai_backend import OpenAILLM
from llm_grop.world.catalog import Catalog
from llm_grop.world.table import Table

if TYPE_CHECKING:
    from conftest import ChatServer

CATALOG = Catalog.load(use_env=False)
CASES = load_cases()
NO_CALLS = Path(__file__).parents[1] / "arrangement" / "no_calls.jsonl"


def test_the_corpus_covers_what_people_write() -> None:
    tags = Counter(t for case in CASES for t in case.tags)
    assert len(CASES) >= 150
    for tag, least in {"meal": 15, "pronoun": 20, "relation": 40, "ambiguous": 5,
                       "diagonal": 10, "stacking": 20, "counts": 15, "diners": 15,
                       "distance": 10, "politeness": 15, "typo": 10, "semicolons": 5,
                       "sentences": 8}.items():
        assert tags[tag] >= least, (tag, tags[tag])


@pytest.mark.parametrize("case", CASES, ids=[c.text[:40] for c in CASES])
def test_a_the_fast_path_reads_exactly_or_leaves_it_to_the_llm(case) -> None:
    fast = read_request(case.text, CATALOG)
    if case.fast:
        assert fast.reading is not None, (fast.unread, fast.doubts)
        assert same(fast.reading, case.expected), fast.reading
    else:
        assert fast.reading is None, f"read wrongly as {fast.reading}"


def openai(server: ChatServer) -> CallLog:
    return CallLog(OpenAILLM(BackendOptions(base_url=server.url, max_retries=0)))


def test_b_a_good_answer_is_carried_through_unchanged(chat_server: ChatServer) -> None:
    log = openai(chat_server)
    wrong = []
    for case in CASES:
        chat_server.reply = lambda body, case=case: answer_of(as_answer(case.expected))
        got = read_with_llm(read_request(case.text, CATALOG), CATALOG, log)
        if not same(got.reading, case.expected):
            wrong.append((case.text, got.reading.meaning(), case.expected.meaning()))
    assert not wrong, "\n".join(map(repr, wrong))
    assert len(chat_server.requests) == len(CASES)


@pytest.mark.parametrize(("text", "reason"), load_refusals())
def test_every_refusal_is_one_line_exit_2(text: str, reason: str, capsys) -> None:
    code = main(["arrange", text, "--llm", "replay", "--replay", str(NO_CALLS)])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    if reason != "contradiction" or "in front of" not in text:
        # Only a request the matcher cannot read alone reaches the (empty) recording.
        assert "no recorded response" not in err, err


def test_a_contradiction_the_llm_reads_is_refused(chat_server: ChatServer) -> None:
    text = "the glass behind the plate and in front of the plate"
    chat_server.reply = lambda body: (
        '{"diners": 1, "objects": [{"name": "water cup", "count": 1, "words": "the glass"}, '
        '{"name": "dinner plate", "count": 1, "words": "the plate"}], "relations": ['
        '{"subject": "water cup", "relation": "above", "reference": "dinner plate", '
        '"distance_cm": null, "partner": null, "words": "the glass behind the plate"}, '
        '{"subject": "water cup", "relation": "below", "reference": "dinner plate", '
        '"distance_cm": null, "partner": null, "words": "in front of the plate"}]}')
    with pytest.raises(BadInput, match="contradict each other: 'the glass behind the plate' "
                                       r"\(the request\); 'in front of the plate'"):
        understand(text, catalog=CATALOG, llm=openai(chat_server), table=Table())


_OBJECTS = ["a plate", "the plate", "two forks", "a fork", "a knife", "a mug", "a coaster",
            "3 strawberries", "a bowl", "a glass of wine", "a napkin", "a spoon", "a lid",
            "the bread plate", "some bread", "a pair of knives", "a mug of coffee"]
_LINKS = ["and", ",", "with", ";", ". Then", "plus", "and also"]
_RELATIONS = ["on", "under", "to the left of", "right of", "beside", "next to", "behind",
              "in front of", "above and to the right of", "at the top left of",
              "2 cm to the left of", "an inch to the right of", "on top of", "either side of"]
_AFTER = ["it", "the plate", "a coaster", "the bowl", "the mug", "the fork"]
_EXTRA = ["please", "thanks!", "if you can", "nothing else", "in the middle", "on its left",
          "on the left", "for two", "for 4 people", "on its upper right"]


@st.composite
def requests(draw: st.DrawFn) -> str:
    parts = [draw(st.sampled_from(_OBJECTS))]
    for _ in range(draw(st.integers(0, 3))):
        parts.append(draw(st.sampled_from(_LINKS)))
        parts.append(draw(st.sampled_from(_OBJECTS)))
        if draw(st.booleans()):
            parts += [draw(st.sampled_from(_RELATIONS)), draw(st.sampled_from(_AFTER))]
        if draw(st.booleans()):
            parts.append(draw(st.sampled_from(_EXTRA)))
    return " ".join(parts)


@settings(max_examples=150, derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(requests())
def test_the_fast_path_and_the_llm_path_agree_on_the_same_answer(
        chat_server: ChatServer, text: str) -> None:
    """A request the fast path reads gives the same reading, words and all, through the
    LLM path when the LLM answers with that reading."""
    try:
        fast = read_request(text, CATALOG)
    except BadInput:
        return
    if fast.reading is None:
        return
    chat_server.reply = lambda body: answer_of(fast.reading)  # type: ignore[arg-type]
    got = read_with_llm(fast, CATALOG, openai(chat_server)).reading
    assert got == replace(fast.reading, read_by="llm")


def test_the_embedded_model_s_readings_are_reported_not_asserted() -> None:
    """(c) is a report: ``benchmarks/phrasings.py --llm embedded`` prints the exact-reading
    rate; here only that its recording of the corpus replays into readings."""
    recording = Path(__file__).parents[2] / "benchmarks" / "data" / "phrasings_embedded.jsonl"
    if not recording.exists():
        pytest.skip("no recording of the embedded model's readings")
    log = make_llm("replay", BackendOptions(replay_path=recording))
    read = 0
    for case in CASES:
        fast = read_request(case.text, CATALOG)
        if fast.reading is not None:
            continue
        try:
            read_with_llm(fast, CATALOG, log)
            read += 1
        except BadInput:
            pass
    assert read > 0
