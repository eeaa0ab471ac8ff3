"""``llm-grop rate`` as a user runs it: scores, run JSON files, exit codes, errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cli_support import one_line_error as _one_line_error
from llm_grop.cli import main

LABELLED = Path(__file__).parent / "evaluation" / "labelled"
GOOD = LABELLED / "08_task8_perfect.json"


@pytest.fixture(autouse=True)
def _no_user_catalog(monkeypatch) -> None:
    monkeypatch.delenv("LLM_GROP_CATALOG", raising=False)


def test_rate_good_file_prints_score_and_checks(capsys) -> None:
    assert main(["rate", str(GOOD)]) == 0
    out = capsys.readouterr().out
    assert "Score: 5/5" in out
    for name in ("all items present", "overlap", "cutlery sides", "drinks upper right"):
        assert name in out
    assert "passed" in out and "skipped" in out


def test_rate_broken_file_shows_the_failed_check_and_writes_json(tmp_path: Path,
                                                                 capsys) -> None:
    out_json = tmp_path / "rating.json"
    code = main(["rate", str(LABELLED / "12_task1_fork_right.json"), "--json", str(out_json)])
    assert code == 0
    out = capsys.readouterr().out
    assert "Score: 3/5" in out and "FAILED" in out and "cutlery sides" in out
    data = json.loads(out_json.read_text())
    assert data["score"] == 3
    assert [c["name"] for c in data["checks"] if not c["passed"]] == ["cutlery sides"]


def test_rate_run_json_rates_final_with_the_run_request(tmp_path: Path, capsys) -> None:
    final = json.loads((LABELLED / "01_task1_perfect.json").read_text())
    del final["request"]
    run = {"method": "llm-grop", "task": 8, "seed": 0, "success": True,
           "request": "set the table with a dinner plate, a dinner fork and a dinner knife",
           "execution_time_s": 100.0, "planning_time_s": 0.1, "steps": [], "final": final}
    path = tmp_path / "run.json"
    path.write_text(json.dumps(run))
    assert main(["rate", str(path)]) == 0
    assert "Score: 5/5" in capsys.readouterr().out
    run["request"] = "set the table with a dinner plate, a dinner fork, a dinner knife and a mug"
    path.write_text(json.dumps(run))
    out_json = tmp_path / "r.json"
    assert main(["rate", str(path), "--json", str(out_json)]) == 0
    assert "Score: 1/5" in capsys.readouterr().out
    failed = [c for c in json.loads(out_json.read_text())["checks"] if not c["passed"]]
    assert failed[0]["name"] == "all items present" and "mug" in failed[0]["detail"]


def test_rate_request_flag_overrides_the_file(capsys) -> None:
    code = main(["rate", str(LABELLED / "01_task1_perfect.json"), "--request",
                 "a dinner plate, two forks and a knife"])
    assert code == 0
    out = capsys.readouterr().out
    assert "Score: 1/5" in out and "dinner fork missing" in out


@pytest.mark.parametrize(("content", "expect"), [
    ("{not json", "not valid JSON"),
    ("[1, 2]", "expected a JSON object"),
    ('{"table": {"size": [0.9, 0.6]}, "objects": [{"name": "mug", "x": "left", "y": 0}]}',
     "objects[0] ('mug').x"),
    ('{"objects": []}', "table"),
    ('{"final": 3}', "final"),
    ('{"final": {"table": {"size": [0.9, 0.6]}, "objects": [{"name": "mug"}]}}',
     "final: objects[0] ('mug').x: required, but missing"),
])
def test_rate_bad_file_is_one_line_error_exit_2(content: str, expect: str, tmp_path: Path,
                                                capsys) -> None:
    path = tmp_path / "bad.json"
    path.write_text(content)
    assert main(["rate", str(path)]) == 2
    line = _one_line_error(capsys)
    assert line.startswith("llm-grop: error:") and expect in line
    assert str(path) in line


def test_rate_missing_file_and_unknown_request_exit_2(tmp_path: Path, capsys) -> None:
    assert main(["rate", str(tmp_path / "nope.json")]) == 2
    assert "nope.json" in _one_line_error(capsys)
    assert main(["rate", str(GOOD), "--request", "a plate and a teapot"]) == 2
    assert "teapot" in _one_line_error(capsys)
