"""The record file and the replay backend, recorded from the openai backend."""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from llm_grop.errors import BadInput, LLMError, ReplayMissing
from llm_grop.llm.base import BackendOptions, CallLog, SamplingParams
from llm_grop.llm.openai_backend import OpenAILLM
from llm_grop.llm.record import LLMCallRecord, append_record, load_records
from llm_grop.llm.registry import create_llm
from llm_grop.llm.replay import ReplayLLM

if TYPE_CHECKING:
    from conftest import ChatServer

CALLS = [
    ("Where does the fork go?", 1),
    ("Où va la fourchette ? 🍴", 1),
    ("Where does the fork go?", 2),
    ("Where does the fork go?", 1),
    ("Where does the fork go?", 1),
    ("unseeded", None),
]

KEYS = ["backend", "model", "prompt", "response", "latency_s", "prompt_tokens",
        "completion_tokens", "seed"]


@dataclass
class CountingReply:
    """Different answers to the same (prompt, seed), numbered by the request count."""

    count: int = 0

    def __call__(self, body: dict[str, Any]) -> str:
        self.count += 1
        return f"answer {self.count} to {body['messages'][-1]['content']}"


def record_run(server: ChatServer, path: Path) -> list[LLMCallRecord]:
    server.reply = CountingReply()
    log = CallLog(OpenAILLM(BackendOptions(base_url=server.url, model="local")), path)
    for prompt, seed in CALLS:
        log.complete(prompt, SamplingParams(seed=seed))
    return log.calls


def replay_run(path: Path) -> list[LLMCallRecord]:
    llm = create_llm("replay", BackendOptions(replay_path=path))
    return [llm.complete(prompt, SamplingParams(seed=seed)) for prompt, seed in CALLS]


def test_file_holds_one_json_line_per_call(chat_server: ChatServer, tmp_path: Path) -> None:
    path = tmp_path / "calls.jsonl"
    recorded = record_run(chat_server, path)
    lines = path.read_text(encoding="utf-8").splitlines()
    assert len(lines) == len(CALLS)
    assert "🍴" in lines[1], "non-ASCII text is written as is"
    for line, record in zip(lines, recorded, strict=True):
        data = json.loads(line)
        assert list(data) == KEYS
        assert data["response"] == record.response
        assert data["latency_s"] == record.latency_s
    assert load_records(path) == recorded


def test_replay_serves_recorded_answers(chat_server: ChatServer, tmp_path: Path) -> None:
    path = tmp_path / "calls.jsonl"
    recorded = record_run(chat_server, path)
    replayed = replay_run(path)
    assert replayed == [replace(record, backend="replay") for record in recorded]
    assert [r.model for r in replayed] == ["local"] * len(CALLS)
    # The key (fork, 1) was recorded three times: served in order.
    fork_1 = [r.response for r, (p, s) in zip(replayed, CALLS, strict=True)
              if (p, s) == ("Where does the fork go?", 1)]
    assert fork_1 == ["answer 1 to Where does the fork go?", "answer 4 to Where does the fork go?",
                      "answer 5 to Where does the fork go?"]


def test_last_answer_repeats(chat_server: ChatServer, tmp_path: Path) -> None:
    path = tmp_path / "calls.jsonl"
    record_run(chat_server, path)
    llm = ReplayLLM(BackendOptions(replay_path=path))
    answers = [llm.complete("Where does the fork go?", SamplingParams(seed=1)).response
               for _ in range(5)]
    assert answers[2:] == ["answer 5 to Where does the fork go?"] * 3


def test_replaying_twice_is_identical(chat_server: ChatServer, tmp_path: Path) -> None:
    path = tmp_path / "calls.jsonl"
    record_run(chat_server, path)
    first, second = tmp_path / "first.jsonl", tmp_path / "second.jsonl"
    for out in (first, second):
        log = CallLog(ReplayLLM(BackendOptions(replay_path=path)), out)
        for prompt, seed in CALLS:
            log.complete(prompt, SamplingParams(seed=seed))
    assert first.read_bytes() == second.read_bytes()
    assert first.read_bytes() == path.read_bytes().replace(b'"backend": "openai"',
                                                           b'"backend": "replay"')


def test_model_names_every_recorded_model(tmp_path: Path) -> None:
    path = tmp_path / "mixed.jsonl"
    for model in ("a", "b", "a"):
        append_record(path, LLMCallRecord("openai", model, f"p{model}", "r", 0.5))
    assert ReplayLLM(BackendOptions(replay_path=path)).model == "a+b"


def test_missing_key(chat_server: ChatServer, tmp_path: Path) -> None:
    path = tmp_path / "calls.jsonl"
    record_run(chat_server, path)
    llm = ReplayLLM(BackendOptions(replay_path=path))
    with pytest.raises(ReplayMissing) as caught:
        llm.complete("Where does the fork go?", SamplingParams(seed=99))
    message = str(caught.value)
    assert message == ("calls.jsonl: no recorded response for prompt 'Where does the fork go?' "
                       "with seed 99 (6 calls recorded)")
    long_prompt = "Objects:\n" + "plate, " * 40
    with pytest.raises(ReplayMissing, match=r"prompt 'Objects: plate, plate, .*…' with seed 3"):
        llm.complete(long_prompt, SamplingParams(seed=3))


@pytest.mark.parametrize(("line", "complaint"), [
    ('{"backend": "openai", ', "malformed replay record: Expecting property name"),
    ('["a list"]', "expected a JSON object"),
    ('{"backend": "openai", "model": "m", "prompt": "p", "latency_s": 1}', "string 'response'"),
    ('{"backend": "openai", "model": "m", "prompt": "p", "response": "r", "latency_s": "1"}',
     "non-negative number 'latency_s'"),
    ('{"backend": "openai", "model": "m", "prompt": "p", "response": "r", "latency_s": 1,'
     ' "seed": 1.5}', "'seed' must be an integer or null"),
])
def test_malformed_line_is_named(tmp_path: Path, line: str, complaint: str) -> None:
    path = tmp_path / "bad.jsonl"
    good = json.dumps({"backend": "openai", "model": "m", "prompt": "p", "response": "r",
                       "latency_s": 0.25})
    path.write_text(f"{good}\n\n{line}\n", encoding="utf-8")
    with pytest.raises(LLMError) as caught:
        ReplayLLM(BackendOptions(replay_path=path))
    message = str(caught.value)
    assert message.startswith(f"{path}:3: ")
    assert complaint in message
    assert "\n" not in message


def test_missing_records_are_defaults(tmp_path: Path) -> None:
    path = tmp_path / "short.jsonl"
    path.write_text('{"backend": "x", "model": "m", "prompt": "p", "response": "r", '
                    '"latency_s": 2}\n', encoding="utf-8")
    assert load_records(path) == [LLMCallRecord("x", "m", "p", "r", 2.0)]


def test_no_replay_file_given() -> None:
    with pytest.raises(BadInput, match="replay backend: no replay file given"):
        create_llm("replay", BackendOptions())


def test_replay_file_not_found(tmp_path: Path) -> None:
    path = tmp_path / "nowhere.jsonl"
    with pytest.raises(LLMError, match=f"^{re.escape(str(path))}: replay file not found$"):
        ReplayLLM(BackendOptions(replay_path=path))


def test_not_utf8_names_the_line(tmp_path: Path) -> None:
    path = tmp_path / "latin1.jsonl"
    path.write_bytes(b'{"a": 1}\n{"prompt": "caf\xe9"}\n')
    with pytest.raises(LLMError, match=r":2: replay file is not UTF-8$"):
        load_records(path)


def test_append_creates_the_folder(tmp_path: Path) -> None:
    path = tmp_path / "deep" / "er" / "calls.jsonl"
    record = LLMCallRecord("embedded", "m", "p", "r", 0.125, 3, 4, 5)
    append_record(path, record)
    append_record(path, record)
    assert load_records(path) == [record, record]


def test_append_to_a_folder_is_bad_input(tmp_path: Path) -> None:
    where = re.escape(str(tmp_path))
    with pytest.raises(BadInput, match=f"^{where}: cannot append the LLM call record"):
        append_record(tmp_path, LLMCallRecord("embedded", "m", "p", "r", 0.1))


def test_each_run_is_served_as_if_it_came_first(chat_server: ChatServer,
                                                tmp_path: Path) -> None:
    # A bench worker or the service keeps one backend for many runs: the order of a key's
    # repeated answers starts afresh in each run's call log, so no run depends on another.
    from llm_grop.assembly import call_log

    path = tmp_path / "calls.jsonl"
    record_run(chat_server, path)
    backend = ReplayLLM(BackendOptions(replay_path=path))
    runs = []
    for _ in range(3):
        log = call_log(backend)
        runs.append([log.complete("Where does the fork go?", SamplingParams(seed=1)).response
                     for _ in range(2)])
    assert runs == [["answer 1 to Where does the fork go?",
                     "answer 4 to Where does the fork go?"]] * 3
