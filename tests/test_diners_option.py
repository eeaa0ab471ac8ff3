"""``--diners N`` (issue 40): one setting of the request (or task) for each of N diners
seated at the target table, through ``run``, ``bench`` and ``arrange`` alike, and its bad
input in one line before any work."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cli_support import one_line_error
from llm_grop.cli import main

EMBEDDED = Path(__file__).parents[1] / "benchmarks" / "data" / "embedded_calls.jsonl"
SETTING = "set the table with a dinner plate, a dinner fork, a dinner knife and a water cup"
NO_LLM = ["--method", "grop", "--llm", "replay", "--replay", str(Path(__file__).parent
                                                                 / "arrangement"
                                                                 / "no_calls.jsonl")]


def test_run_sets_the_request_for_each_of_six_diners(tmp_path: Path) -> None:
    out = tmp_path / "run.json"
    assert main(["run", SETTING, "--diners", "6", "--table", "2.4x1.0", *NO_LLM,
                 "--json", str(out), "-q"]) in (0, 1)
    doc = json.loads(out.read_text())
    table = doc["final"]["table"]
    assert len(table["diners"]) == 6
    planned = doc["planned"]["objects"]
    assert len(planned) == 24
    assert sorted({o["diner"] for o in planned}) == list(range(6))
    assert {o["name"] for o in planned} >= {"dinner plate", "dinner plate 6", "water cup 6"}


def test_bench_seats_four_diners_round_a_round_table(tmp_path: Path) -> None:
    out = tmp_path / "bench"
    assert main(["bench", "--tasks", "1", "--trials", "1", "--methods", "grop",
                 "--diners", "4", "--table", "round:1.4", "--llm", "replay", "--replay",
                 NO_LLM[-1], "--no-images", "--out", str(out), "-q"]) == 0
    row = json.loads((out / "trials.jsonl").read_text().splitlines()[0])
    assert len(row["final"]["table"]["diners"]) == 4
    assert row["final"]["table"]["shape"] == "circle"
    objects = {o["name"] for o in row["final"]["objects"]} | set(row["unplaced"])
    assert len(objects) == 4 * 3  # task 1: three objects for each diner


def test_arrange_seats_the_diners_it_is_told(tmp_path: Path) -> None:
    out = tmp_path / "a.json"
    assert main(["arrange", "--task", "1", "--diners", "3", "--table", "1.8x0.9",
                 "--llm", "replay", "--replay", str(EMBEDDED), "--json", str(out), "-q"]) == 0
    doc = json.loads(out.read_text())
    assert len(doc["table"]["diners"]) == 3 and len(doc["objects"]) == 9


@pytest.mark.parametrize(("args", "needle"), [
    (["--diners", "8", "--table", "0.9x0.6"], "8 diners do not fit at the 0.9 x 0.6 m table"),
    (["--diners", "13"], "'--diners': 13 is not in the range 1<=x<=12"),
    (["--diners", "0"], "'--diners': 0 is not in the range 1<=x<=12"),
])
def test_bad_diners_are_one_line_before_any_work(args: list[str], needle: str, capsys,
                                                 tmp_path: Path) -> None:
    out = tmp_path / "run.json"
    assert main(["run", "a dinner plate and a dinner fork", *args, *NO_LLM,
                 "--json", str(out), "-q"]) == 2
    assert needle in one_line_error(capsys)
    assert not out.exists()


def test_diners_against_the_request_s_own_count_is_one_line(capsys) -> None:
    assert main(["run", "set the table for two with a dinner plate", "--diners", "4",
                 *NO_LLM, "-q"]) == 2
    assert "2 diners' settings but 4 seats" in one_line_error(capsys)


def test_diners_against_a_scene_s_seats_is_one_line(tmp_path: Path, capsys) -> None:
    import yaml

    from llm_grop.files.scene_file import load_scene, scene_to_dict

    doc = scene_to_dict(load_scene()) | {"diners": [[0.0, -0.5, 1.5708], [0.0, 0.5, -1.5708]]}
    scene = tmp_path / "seated.yaml"
    scene.write_text(yaml.safe_dump(doc))
    assert main(["run", "a dinner plate", "--scene", str(scene), "--diners", "3", *NO_LLM,
                 "-q"]) == 2
    assert "3 diners, but the scene's 'dining table' seats 2" in one_line_error(capsys)
