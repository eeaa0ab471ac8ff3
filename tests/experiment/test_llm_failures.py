"""A bench that keeps going when the LLM fails: such trials are recorded ``llm-failed``,
left out of the summary, and retried by a rerun; ``--max-failed`` stops a bench whose
server is down."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from llm_grop.cli import main
from scripted import TASK1_GOOD, scripted


def _bench(server, out: Path, *extra: str) -> int:
    return main(["bench", "--tasks", "1", "--trials", "4", "--methods", "latp,llm-grop",
                 "--llm", "openai", "--base-url", server.url, "--retries", "0",
                 "--no-cache", "--no-images", "--out", str(out), "-q", *extra])


def _rows(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "trials.jsonl").read_text().splitlines()]


def test_failed_trials_are_kept_apart_and_retried_by_a_rerun(chat_server,
                                                             tmp_path: Path) -> None:
    chat_server.reply = scripted([TASK1_GOOD])
    chat_server.plan.extend(([200, 200, 500] * 200)[:300])  # a third of the calls fail
    out = tmp_path / "bench"
    assert _bench(chat_server, out) == 0
    first = _rows(out)
    failed = [r for r in first if r["status"] == "llm-failed"]
    assert len(first) == 8 and failed, "some trials should have failed"
    assert all("answered 500" in r["reason"] for r in failed)
    summary = json.loads((out / "summary.json").read_text())
    assert sum(summary["llm_failed"].values()) == len(failed)
    assert sum(m["trials"] for m in summary["methods"]) == 8 - len(failed)
    assert "Left out:" in (out / "summary.md").read_text()

    chat_server.plan.clear()
    asked = len(chat_server.requests)
    assert _bench(chat_server, out) == 0
    again = _rows(out)
    assert len(again) == 8 and all(r["status"] == "ok" for r in again)
    kept = {(r["method"], r["trial"]): r for r in again}
    for r in first:
        if r["status"] == "ok":  # a trial that succeeded was not run again
            assert kept[(r["method"], r["trial"])]["llm_calls"] == r["llm_calls"]
    assert len(chat_server.requests) > asked
    assert "llm_failed" not in json.loads((out / "summary.json").read_text())


def test_max_failed_stops_a_bench_whose_server_is_down(chat_server, tmp_path: Path,
                                                       capsys) -> None:
    chat_server.plan.extend([503] * 1000)
    out = tmp_path / "down"
    assert _bench(chat_server, out, "--max-failed", "2") == 3  # the service is unavailable
    err = capsys.readouterr().err.strip()
    assert err.startswith("llm-grop: error: --max-failed 2: 2 trials got no usable LLM answer")
    assert err.endswith("stopped early, every finished trial is saved; rerun to retry them")
    assert "\n" not in err
    rows = _rows(out)
    assert 2 <= len(rows) < 8 and all(r["status"] == "llm-failed" for r in rows)


@pytest.mark.parametrize(("answer", "reason"), [
    ("x" * 3000, "larger than 2000 bytes"),
    ("I would rather not say where things go.", "gave no usable spatial relation"),
])
def test_an_oversized_or_unreadable_answer_is_a_failed_trial_not_a_stop(
        chat_server, tmp_path: Path, answer: str, reason: str) -> None:
    """Answers that asking again may cure (too large, prose with no relation in it) become
    llm-failed rows, and the bench goes on to its other trials."""
    chat_server.reply = scripted([answer])
    out = tmp_path / "bench"
    assert _bench(chat_server, out, "--max-answer-bytes", "2000") == 0
    rows = _rows(out)
    assert len(rows) == 8 and {r["status"] for r in rows} == {"llm-failed"}
    assert all(reason in r["reason"] for r in rows)


def _setup_no_reply(server) -> None:
    server.raw.extend([b'{"choices": []}'] * 1000)


def _setup_garbled(server) -> None:
    server.raw.extend([b"<html>502 Bad Gateway</html>"] * 1000)


def _setup_silent(server) -> None:
    server.delay_s = 4.0  # past --timeout 1


@pytest.mark.parametrize(("setup", "reason"), [
    (_setup_no_reply, "malformed answer from"),
    (_setup_garbled, "unreadable answer from"),
    (_setup_silent, "no answer within the 1 s deadline"),
], ids=["JSON without a reply", "no JSON", "past --timeout"])
def test_every_answer_a_retry_may_cure_is_a_failed_trial(chat_server, tmp_path: Path, setup,
                                                         reason: str) -> None:
    """A bench on the 2D simulator and the local executor, against a server that answers
    200 with no reply, 200 with no JSON, or nothing within --timeout: every trial is an
    llm-failed row with the reason, the bench goes on to the end, and a rerun against a
    mended server finishes them."""
    setup(chat_server)
    out = tmp_path / "bench"
    args = ["--trials", "2", "--timeout", "1", "--executor", "local",
            "--simulator", "kinematic2d"]
    assert _bench(chat_server, out, *args) == 0
    rows = _rows(out)
    assert len(rows) == 4 and {r["status"] for r in rows} == {"llm-failed"}
    assert all(reason in r["reason"] for r in rows), [r["reason"] for r in rows]

    chat_server.raw.clear()
    chat_server.delay_s = 0.0
    chat_server.reply = scripted([TASK1_GOOD])
    assert _bench(chat_server, out, *args) == 0
    assert {r["status"] for r in _rows(out)} == {"ok"}


def test_a_request_the_server_refuses_stops_the_bench(chat_server, tmp_path: Path,
                                                      capsys) -> None:
    """A 4xx other than 408, 409 and 429 (here 400, as for a prompt over the model's
    context) refuses the request itself: asking again gets the same, so the bench stops
    with bad input (2), as the README lists."""
    chat_server.plan.extend([400] * 1000)
    out = tmp_path / "refused"
    assert _bench(chat_server, out, "--executor", "local") == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"llm-grop: error: openai backend: {chat_server.url} answered 400 "
                   "(planned failure 400)")
    assert not (out / "trials.jsonl").exists() or not _rows(out)
