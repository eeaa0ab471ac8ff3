"""`llm-grop bench` end to end: rows, resume, determinism, refusals and bad input."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import jsonschema
import pytest

from llm_grop.cli import main
from llm_grop.contract.schemas import json_schema
from llm_grop.experiment.trial import RUN_DEPENDENT_FIELDS

RECORDING = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "embedded_calls.jsonl"
BASE = ["bench", "--tasks", "1", "--trials", "2", "--llm", "replay", "--replay", str(RECORDING),
        "-q"]


def _rows(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "trials.jsonl").read_text().splitlines()]


def _stable(rows: list[dict]) -> list[dict]:
    for row in rows:
        for key in RUN_DEPENDENT_FIELDS:
            row.pop(key, None)
    return rows


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    return err


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("bench") / "run"
    assert main(BASE + ["--out", str(out), "--workers", "2"]) == 0
    return out


def test_two_trial_bench_runs_end_to_end(finished: Path) -> None:
    rows = _rows(finished)
    keys = [(r["task"], r["trial"], r["method"]) for r in rows]
    assert keys == sorted(keys) and len(keys) == 8
    assert {r["method"] for r in rows} == {"tpra", "latp", "grop", "llm-grop"}
    validator = jsonschema.Draft202012Validator(json_schema("trial"))
    for r in rows:
        validator.validate(r)
        assert r["simulator"] == "kinematic2d"
        assert {"method", "task", "seed", "success", "execution_time_s", "planning_time_s",
                "final", "rating", "rating_explanation", "llm_calls", "retries"} <= r.keys()
        assert 1 <= r["rating"] <= 5
        assert r["seed"] == r["trial"]
        assert (finished / r["image"]).stat().st_size > 0
        if r["method"] in {"latp", "llm-grop"}:
            assert r["llm_calls"] > 0
        else:
            assert r["llm_calls"] == 0
    # Paired: every method of a trial saw the same chairs.
    chairs = {(r["trial"], json.dumps(r["scene"]["chairs"])) for r in rows if "scene" in r}
    assert len({t for t, _ in chairs}) == len(chairs)
    for name in ("summary.json", "summary.md", "fig3_rating_vs_time.png",
                 "fig5_rating_per_task.png", "experiment.json"):
        assert (finished / name).stat().st_size > 0


def test_resume_changes_nothing(finished: Path) -> None:
    before = (finished / "trials.jsonl").read_bytes()
    summary = (finished / "summary.json").read_bytes()
    assert main(BASE + ["--out", str(finished)]) == 0
    assert (finished / "trials.jsonl").read_bytes() == before
    assert (finished / "summary.json").read_bytes() == summary


def test_interrupted_run_resumes_to_the_same_rows(finished: Path, tmp_path: Path) -> None:
    out = tmp_path / "partial"
    assert main(BASE + ["--out", str(out), "--methods", "grop"]) == 0
    lines = (out / "trials.jsonl").read_text().splitlines()
    # As if killed while writing the second row: the cut-off row is redone.
    (out / "trials.jsonl").write_text(lines[0] + "\n" + lines[1][:40])
    assert main(BASE + ["--out", str(out), "--methods", "grop"]) == 0
    assert _stable(_rows(out)) == _stable([r for r in _rows(finished) if r["method"] == "grop"])


def test_same_seed_same_jsonl(finished: Path, tmp_path: Path) -> None:
    out = tmp_path / "again"
    assert main(BASE + ["--out", str(out), "--workers", "1"]) == 0
    assert _stable(_rows(out)) == _stable(_rows(finished))


def test_other_experiment_is_refused(finished: Path, capsys) -> None:
    before = (finished / "trials.jsonl").read_bytes()
    assert main(BASE + ["--out", str(finished), "--chairs", "3"]) == 2
    assert "holds another experiment's results (different chairs)" in _one_line_error(capsys)
    assert (finished / "trials.jsonl").read_bytes() == before


def test_non_empty_directory_is_refused(tmp_path: Path, capsys) -> None:
    (tmp_path / "notes.txt").write_text("mine")
    assert main(BASE + ["--out", str(tmp_path)]) == 2
    assert "not empty" in _one_line_error(capsys)


@pytest.mark.parametrize(("extra", "needle"), [
    (["--methods", "tpra,magic"], "--methods: unknown method 'magic'"),
    (["--tasks", "9"], "unknown task 9"),
    (["--tasks", "dinner"], "no task is tagged 'dinner'"),
    (["--tasks", "3-1"], "'3-1' is an empty range"),
    (["--seed", "-1"], "--seed"),
    (["--simulator", "gazebo"], "--simulator: unknown simulator 'gazebo'"),
    (["--llm", "claude"], "--llm: unknown backend 'claude'"),
    (["--replay", "/nonexistent/calls.jsonl"], "calls.jsonl: replay file not found"),
    (["--prefer", "the dinner fork to the left of the dinner plate",
      "--prefer", "the dinner plate to the left of the dinner fork"],
     "task 1: preferences contradict each other"),
])
def test_bad_flags(tmp_path: Path, capsys, extra: list[str], needle: str) -> None:
    assert main(BASE + ["--out", str(tmp_path / "x")] + extra) == 2
    assert needle in _one_line_error(capsys)
    assert not (tmp_path / "x").exists()


def test_user_task_file(tmp_path: Path, capsys) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("tasks:\n  - id: 9\n    objects: []\n")
    assert main(BASE + ["--out", str(tmp_path / "x"), "--task-file", str(bad),
                        "--tasks", "9"]) == 2
    assert "bad.yaml" in _one_line_error(capsys)
    good = tmp_path / "good.yaml"
    good.write_text("tasks:\n  - id: 9\n    objects: [dinner plate, mug]\n    tags: [mine]\n")
    out = tmp_path / "mine"
    assert main(["bench", "--tasks", "mine", "--trials", "1", "--methods", "tpra,grop",
                 "--task-file", str(good), "--out", str(out), "--no-images", "-q"]) == 0
    rows = _rows(out)
    assert [r["task"] for r in rows] == [9, 9] and "image" not in rows[0]


def _bench_process(out: Path, workers: int, stdout: int) -> subprocess.Popen[bytes]:
    """``bench`` with :data:`BASE` into ``out``, started in a process of its own (its
    stderr piped)."""
    import sys

    cmd = [sys.executable, "-c", "import sys; from llm_grop.cli import main; "
           "sys.exit(main(sys.argv[1:]))", *BASE, "--out", str(out), "--workers", str(workers)]
    return subprocess.Popen(cmd, stdout=stdout, stderr=subprocess.PIPE)


def test_ctrl_c_loses_no_finished_trial(finished: Path, tmp_path: Path) -> None:
    import signal
    import subprocess
    import time

    out = tmp_path / "interrupted"
    proc = _bench_process(out, 2, subprocess.PIPE)
    rows = out / "trials.jsonl"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if rows.exists() and rows.read_text().count("\n") >= 1:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    if proc.returncode == 130:
        assert b"rerun the same command to resume" in err
        assert b"Traceback" not in err
    else:  # the bench finished before the signal arrived
        assert proc.returncode == 0
    saved = _rows(out)
    assert saved
    assert main(BASE + ["--out", str(out)]) == 0
    assert _stable(_rows(out)) == _stable(_rows(finished))


def test_the_llm_cache_answers_a_second_bench(tmp_path: Path) -> None:
    cache = tmp_path / "cache"
    args = BASE + ["--methods", "latp,llm-grop", "--no-images", "--cache-dir", str(cache)]
    assert main(args + ["--out", str(tmp_path / "first")]) == 0
    first = _rows(tmp_path / "first")
    # The two methods ask the same Template 1 questions with the same seeds.
    assert sum(r["llm_cache_hits"] for r in first) > 0
    assert main(args + ["--out", str(tmp_path / "second")]) == 0
    second = _rows(tmp_path / "second")
    assert all(r["llm_cache_hits"] == r["llm_calls"] > 0 for r in second)
    assert _stable(second) == _stable(first)
    entries = len(list(cache.glob("*/*.json")))
    assert main(BASE + ["--methods", "llm-grop", "--no-images", "--no-cache", "--cache-dir",
                        str(cache), "--out", str(tmp_path / "third")]) == 0
    assert all(r["llm_cache_hits"] == 0 for r in _rows(tmp_path / "third"))
    assert len(list(cache.glob("*/*.json"))) == entries


def test_an_unwritable_cache_directory_is_refused_before_any_trial(tmp_path: Path,
                                                                   capsys) -> None:
    (tmp_path / "file").write_text("")
    assert main(BASE + ["--out", str(tmp_path / "x"), "--cache-dir",
                        str(tmp_path / "file")]) == 2
    assert "--cache-dir" in _one_line_error(capsys) and not (tmp_path / "x").exists()


def test_an_unusable_default_cache_is_left_out_with_a_warning(tmp_path: Path, monkeypatch,
                                                              capsys) -> None:
    (tmp_path / "file").write_text("")
    monkeypatch.setenv("LLM_GROP_CACHE_DIR", str(tmp_path / "file"))
    assert main(["bench", "--tasks", "1", "--trials", "1", "--methods", "llm-grop",
                 "--llm", "replay", "--replay", str(RECORDING), "--no-images",
                 "--out", str(tmp_path / "x")]) == 0
    assert "no LLM cache: the default" in capsys.readouterr().err
    assert [r["llm_cache_hits"] for r in _rows(tmp_path / "x")] == [0]


def test_a_second_bench_on_one_directory_is_refused(finished: Path, tmp_path: Path,
                                                    capsys) -> None:
    import subprocess
    import time

    out = tmp_path / "shared"
    first = _bench_process(out, 1, subprocess.DEVNULL)
    lock = out / ".lock"
    deadline = time.monotonic() + 120
    while not (lock.exists() and lock.read_text().strip()) and first.poll() is None:
        assert time.monotonic() < deadline
        time.sleep(0.02)
    # The first holds the lock from before its first trial to after its last (eight
    # trials, seconds); the second is refused at once.
    assert main(BASE + ["--out", str(out)]) == 2
    assert first.poll() is None
    assert _one_line_error(capsys) == (
        f"llm-grop: error: --out {out}: in use by another llm-grop run on this directory "
        f"(pid {first.pid}); wait for it to end or stop it")
    assert first.wait(timeout=300) == 0
    assert _stable(_rows(out)) == _stable(_rows(finished))  # exact: each trial once


def test_resume_removes_duplicate_rows_keeping_the_first(finished: Path,
                                                         tmp_path: Path) -> None:
    import shutil

    out = tmp_path / "doubled"
    shutil.copytree(finished, out)
    lines = (out / "trials.jsonl").read_text().splitlines(keepends=True)
    changed = json.loads(lines[0]) | {"planning_time_s": 999.0}  # a later copy of trial 1
    (out / "trials.jsonl").write_text("".join(lines + [json.dumps(changed) + "\n"] + lines))
    assert main(BASE + ["--out", str(out)]) == 0
    assert _rows(out) == _rows(finished)
    summary = json.loads((out / "summary.json").read_text())
    assert summary == json.loads((finished / "summary.json").read_text())


def test_the_experiment_names_the_profile_auto_chose(tmp_path: Path) -> None:
    """``--feasibility auto`` (the default) is resolved before the experiment's identity
    is written: a 3D bench plans with, and names, the profile fitted in MuJoCo."""
    from llm_grop.cli.bench import prepare_experiment
    from llm_grop.experiment.runner import identity
    from llm_grop.settings import RunSettings

    def named(**values) -> str:
        exp = prepare_experiment(RunSettings(**values), tasks_text="1", trials=1,
                                 methods_text="grop", out_dir=tmp_path / "out",
                                 no_images=True, threads=None)
        return identity(exp)["feasibility"]

    assert named(simulator="mujoco") == "mujoco"
    assert named() == "default"
    assert named(truth="mujoco") == "mujoco"
    assert named(simulator="mujoco", feasibility="default") == "default"
