"""The shared LLM answer cache: identical calls answered once, on disk, by any process."""

from __future__ import annotations

import json
import multiprocessing
from dataclasses import replace
from pathlib import Path

import pytest

from llm_grop.api import make_llm
from llm_grop.llm.base import BackendOptions, CallLog, SamplingParams
from llm_grop.llm.cache import CallKey, LLMCache
from llm_grop.llm.record import LLMCallRecord, append_record, load_records
from llm_grop.llm.replay import ReplayLLM

PARAMS = SamplingParams(seed=7)


def _log(server, cache: Path | None, model: str = "m1") -> CallLog:
    return make_llm("openai", BackendOptions(base_url=server.url, api_key="k", model=model,
                                             max_retries=0), cache=cache)


def test_identical_calls_are_answered_once(chat_server, tmp_path: Path) -> None:
    first = _log(chat_server, tmp_path).complete("set the table", PARAMS)
    # Another log over another backend object, as another method or bench cell has.
    again = _log(chat_server, tmp_path).complete("set the table", PARAMS)
    assert len(chat_server.requests) == 1
    assert not first.cached and again.cached
    assert again.response == first.response and again.latency_s == first.latency_s
    assert replace(again, cached=False) == first


@pytest.mark.parametrize("change", [
    {"prompt": "set the table, please"},
    {"params": SamplingParams(seed=8)},
    {"params": SamplingParams(seed=7, temperature=0.5)},
    {"params": SamplingParams(seed=7, max_tokens=64)},
    {"model": "m2"},
    {"grammar": 'root ::= "a"'},
])
def test_anything_that_decides_the_answer_is_in_the_key(chat_server, tmp_path: Path,
                                                         change: dict) -> None:
    _log(chat_server, tmp_path).complete("set the table", PARAMS)
    log = _log(chat_server, tmp_path, change.get("model", "m1"))
    record = log.complete(change.get("prompt", "set the table"),
                          change.get("params", PARAMS), change.get("grammar"))
    assert not record.cached and len(chat_server.requests) == 2


def test_unseeded_calls_are_never_cached(chat_server, tmp_path: Path) -> None:
    for _ in range(2):
        assert not _log(chat_server, tmp_path).complete("hi", SamplingParams()).cached
    assert len(chat_server.requests) == 2 and not any(tmp_path.iterdir())


def test_no_cache_asks_every_time(chat_server) -> None:
    for _ in range(2):
        assert not _log(chat_server, None).complete("hi", PARAMS).cached
    assert len(chat_server.requests) == 2


def test_replay_files_with_other_answers_do_not_share_entries(tmp_path: Path) -> None:
    answers = []
    for k, response in enumerate(("plate left", "plate right")):
        path = tmp_path / f"rec{k}.jsonl"
        append_record(path, LLMCallRecord("embedded", "m", "p", response, 0.1, seed=7))
        log = make_llm(ReplayLLM(BackendOptions(replay_path=path)), cache=tmp_path / "c")
        answers.append(log.complete("p", PARAMS).response)
    assert answers == ["plate left", "plate right"]


def test_cache_hits_are_marked_in_the_log_and_the_record_file(chat_server,
                                                              tmp_path: Path) -> None:
    record = tmp_path / "calls.jsonl"
    for _ in range(2):
        log = make_llm("openai", BackendOptions(base_url=chat_server.url, api_key="k",
                                                max_retries=0), record=record,
                       cache=tmp_path / "cache")
        log.complete("p", PARAMS)
    assert log.cache_hits == 1
    lines = [json.loads(line) for line in record.read_text().splitlines()]
    assert "cached" not in lines[0] and lines[1]["cached"] is True
    # A record file with cache hits still replays.
    assert [r.response for r in load_records(record)] == [lines[0]["response"]] * 2


POISONS = {
    "not json": lambda d, text: "{not json",
    "truncated": lambda d, text: text[: len(text) // 2],
    "null answer": lambda d, text: json.dumps(d | {"record": d["record"] | {"response": None}}),
    "a number": lambda d, text: json.dumps(d | {"record": 42}),
    "the whole entry null": lambda d, text: "null",
    "a negative latency": lambda d, text: json.dumps(
        d | {"record": d["record"] | {"latency_s": -1}}),
}


@pytest.mark.parametrize("poison", sorted(POISONS))
def test_a_damaged_entry_is_asked_again_and_rewritten(chat_server, tmp_path: Path, poison: str,
                                                       caplog) -> None:
    first = _log(chat_server, tmp_path).complete("p", PARAMS)
    (entry,) = tmp_path.glob("*/*.json")
    text = entry.read_text()
    entry.write_text(POISONS[poison](json.loads(text), text))
    with caplog.at_level("WARNING", logger="llm_grop.llm.cache"):
        again = _log(chat_server, tmp_path).complete("p", PARAMS)
    assert not again.cached and again.response == first.response
    assert len(chat_server.requests) == 2
    assert [r.message for r in caplog.records if "ignoring bad entry" in r.message]
    rewritten, original = json.loads(entry.read_text()), json.loads(text)  # rewritten whole
    assert rewritten["key"] == original["key"]
    assert rewritten["record"]["response"] == original["record"]["response"]
    assert _log(chat_server, tmp_path).complete("p", PARAMS).cached


def test_an_entry_under_another_keys_name_is_not_served(chat_server, tmp_path: Path) -> None:
    log = _log(chat_server, tmp_path)
    log.complete("p", PARAMS)
    log.complete("q", PARAMS)
    p_entry, q_entry = sorted(tmp_path.glob("*/*.json"),
                              key=lambda f: json.loads(f.read_text())["key"]["prompt"])
    q_entry.write_text(p_entry.read_text())  # p's answer copied under q's name
    answer = _log(chat_server, tmp_path).complete("q", PARAMS)
    assert not answer.cached and answer.prompt == "q"
    assert json.loads(q_entry.read_text())["key"]["prompt"] == "q"


def _writer(root: str, worker: int, keys: int) -> None:
    cache = LLMCache(root)
    for k in range(keys):
        # Half the keys are shared by every writer, half are the writer's own.
        prompt = f"shared {k}" if k % 2 == 0 else f"own {worker} {k}"
        key = CallKey("openai", "openai:x", prompt, {"seed": k}, None, None)
        cache.put(key, LLMCallRecord("openai", "x", prompt, f"answer {prompt}", 0.5, seed=k))
        got = cache.get(key)
        assert got is not None and got.response == f"answer {prompt}"


def test_concurrent_writers_leave_whole_entries(tmp_path: Path) -> None:
    ctx = multiprocessing.get_context("spawn")
    procs = [ctx.Process(target=_writer, args=(str(tmp_path), w, 60)) for w in range(4)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(timeout=120)
    assert [p.exitcode for p in procs] == [0, 0, 0, 0]
    entries = list(tmp_path.glob("*/*.json"))
    assert len(entries) == 30 + 4 * 30
    assert not list(tmp_path.glob("*/.*"))  # no temporary file is left behind
    for entry in entries:
        data = json.loads(entry.read_text())
        assert data["record"]["response"] == f"answer {data['key']['prompt']}"


@pytest.mark.parametrize("special", ["fifo", "symlink to /dev/zero", "oversized answer"])
def test_an_entry_that_is_no_regular_file_or_too_large_is_a_miss(
        chat_server, tmp_path: Path, special: str, caplog) -> None:
    """A FIFO never blocks the call, a link to an endless device is never read, and an
    answer over --max-answer-bytes is never served from the cache."""
    import os

    first = _log(chat_server, tmp_path).complete("p", PARAMS)
    (entry,) = tmp_path.glob("*/*.json")
    if special == "fifo":
        entry.unlink()
        os.mkfifo(entry)
    elif special == "symlink to /dev/zero":
        entry.unlink()
        entry.symlink_to("/dev/zero")
    else:
        data = json.loads(entry.read_text())
        data["record"]["response"] = "x" * 2_000_000
        entry.write_text(json.dumps(data))
    with caplog.at_level("WARNING", logger="llm_grop.llm.cache"):
        again = _log(chat_server, tmp_path).complete("p", PARAMS)
    assert not again.cached and again.response == first.response
    assert [r.message for r in caplog.records if "ignoring bad entry" in r.message]
    assert entry.is_file() and not entry.is_symlink()  # rewritten as a regular entry
    assert _log(chat_server, tmp_path).complete("p", PARAMS).cached
