"""`llm-grop ratings`: each command as a user types it, and one-line errors for bad input."""

from __future__ import annotations

import csv
import io
import sqlite3
from pathlib import Path

import pytest

from llm_grop.cli import main
from llm_grop.ratings.store import EXPORT_COLUMNS
from ratings_support import ADMIN, RECORDING, load_benchmark


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err, err
    return err


def test_create_invite_export_report(bench_dir: Path, tmp_path: Path, capsys) -> None:
    db = tmp_path / "study.db"
    assert main(["ratings", "create", "--bench", str(bench_dir), "--db", str(db),
                 "--name", "pilot"]) == 0
    out = capsys.readouterr().out
    assert "Study 'pilot': 16 pictures of tasks 1, 2 by 4 methods" in out
    assert main(["ratings", "invite", "--db", str(db), "--count", "2"]) == 0
    codes = capsys.readouterr().out.split()
    assert len(codes) == 2
    with sqlite3.connect(db) as conn:
        items = [r[0] for r in conn.execute("SELECT id FROM items")]
        conn.executemany("INSERT INTO ratings VALUES (?, ?, ?, ?)",
                         [(r, item, 1 + (k + r) % 5, f"2026-01-01T00:00:{k:02d}")
                          for r in (1, 2) for k, item in enumerate(items)])
    target = tmp_path / "ratings.csv"
    assert main(["ratings", "export", "--db", str(db), "--csv", str(target)]) == 0
    rows = list(csv.DictReader(io.StringIO(target.read_text())))
    assert len(rows) == 32 and tuple(rows[0]) == EXPORT_COLUMNS
    assert main(["ratings", "export", "--db", str(db), "--csv", "-"]) == 0
    assert capsys.readouterr().out == target.read_text()
    report = tmp_path / "report"
    assert main(["ratings", "report", "--db", str(db), "--out", str(report)]) == 0
    out = capsys.readouterr().out
    assert "32 ratings of 16 of the 16 pictures by 2 raters" in out
    assert "Krippendorff" in out
    assert (report / "report.md").exists() and (report / "fig5_rating_per_task.png").exists()


@pytest.mark.parametrize(("args", "needle"), [
    (["create", "--bench", "{tmp}/none", "--db", "{tmp}/s.db"], "no trials.jsonl"),
    (["create", "--bench", "{bench}", "--db", "{tmp}/no/such/dir/s.db"], "--db"),
    (["create", "--bench", "{bench}", "--db", "{study}"], "already exists"),
    (["invite", "--db", "{tmp}/missing.db", "--count", "2"], "no such study database"),
    (["invite", "--db", "{study}", "--count", "0"], "--count 0: invite between 1 and 1000"),
    (["invite", "--db", "{text}", "--count", "1"], "not an llm-grop study database"),
    (["export", "--db", "{study}", "--csv", "{tmp}"], "is a directory"),
    (["report", "--db", "{study}", "--out", "{text}"], "is a file"),
    (["report", "--db", "{study}", "--out", "{tmp}/r"], "no rating yet"),
    (["serve", "--db", "{study}", "--admin-token", "short"], "at least 16 characters"),
    (["serve", "--db", "{missing}"], "no such study database"),
    (["serve", "--db", "{study}", "--port", "70000"], "70000"),
    (["serve", "--db", "{study}", "--host", "192.0.2.1", "--admin-token", ADMIN],
     "cannot listen"),
])
def test_bad_input_is_one_line(bench_dir: Path, study, tmp_path: Path, capsys, args, needle
                               ) -> None:
    text = tmp_path / "text.txt"
    text.write_text("not a database, not a directory " * 10)
    values = {"tmp": tmp_path, "bench": bench_dir, "study": study[0], "text": text,
              "missing": tmp_path / "missing.db"}
    argv = ["ratings", *(a.format(**values) for a in args)]
    assert main(argv) == 2
    err = one_line_error(capsys)
    assert err.startswith("llm-grop: error: ") and needle in err, err


def test_a_sweep_directory_is_refused_with_its_cells(tmp_path: Path, capsys) -> None:
    sweep = tmp_path / "s.yaml"
    sweep.write_text(f"tasks: 1\nmethods: grop\ntrials: 1\n"
                     f"llm: {{backend: replay, replay: {RECORDING}}}\n"
                     "grid: {weight: [5, 10, 20, 40, 80, 160, 320]}\n")
    out = tmp_path / "out"
    assert main(["sweep", str(sweep), "--out", str(out), "-q"]) == 0
    db = tmp_path / "s.db"
    assert main(["ratings", "create", "--bench", f"{out}/", "--db", str(db)]) == 2
    cells = ", ".join(f"{out}/weight={w}" for w in (5, 10, 20, 40, 80, 160))
    assert one_line_error(capsys) == (f"llm-grop: error: --bench {out}: a sweep directory; "
                                      f"choose one of its cells: {cells} and 1 more")
    assert not db.exists()
    # A cell it lists is a bench directory a study is made of.
    assert main(["ratings", "create", "--bench", str(out / "weight=320"), "--db", str(db)]) == 0
    assert "Study 'weight=320': 1 picture of task 1 by 1 method, in " in capsys.readouterr().out


def test_serve_refuses_a_port_in_use(study, capsys) -> None:
    load = load_benchmark("ratings_load")
    with load.serving(study[0]) as url:
        port = url.rsplit(":", 1)[1].strip("/")
        assert main(["ratings", "serve", "--db", str(study[0]), "--port", port,
                     "--admin-token", ADMIN]) == 2
    assert f"--port {port}: cannot listen" in one_line_error(capsys)


def test_load_with_a_smaller_count(study) -> None:
    """The load test, small: every rating stored exactly once, none refused."""
    load = load_benchmark("ratings_load")
    db, codes = study
    with load.serving(db) as url:
        result = load.drive(url, codes, per_rater=16, timeout_s=120)
    assert result.errors == []
    assert load.stored(db) == (48, 48)
    assert len(result.rate_s) == 48
