"""`llm-grop sweep`: cells from a grid, resumable, a summary across them, bad files."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from llm_grop.cli import main
from llm_grop.errors import BadInput
from llm_grop.experiment.sweep import load_sweep
from llm_grop.experiment.trial import RUN_DEPENDENT_FIELDS

RECORDING = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "embedded_calls.jsonl"
SWEEP = f"""\
tasks: [1]
methods: grop,llm-grop
trials: 2
images: false
llm: {{backend: replay, replay: {RECORDING}}}
grid:
  weight: [20, 40.5]
  chairs: [0, 2]
"""


def _rows(out: Path) -> list[dict]:
    return [{k: v for k, v in json.loads(line).items() if k not in RUN_DEPENDENT_FIELDS}
            for line in (out / "trials.jsonl").read_text().splitlines()]


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    return err


@pytest.fixture(scope="module")
def swept(tmp_path_factory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("sweep")
    (root / "sweep.yaml").write_text(SWEEP)
    assert main(["sweep", str(root / "sweep.yaml"), "--out", str(root / "out"), "-q",
                 "--workers", "2"]) == 0
    return root / "sweep.yaml", root / "out"


def test_every_combination_is_a_bench_directory(swept: tuple[Path, Path]) -> None:
    path, out = swept
    names = ["weight=20,chairs=0", "weight=20,chairs=2", "weight=40.5,chairs=0",
             "weight=40.5,chairs=2"]
    assert [c.name for c in load_sweep(path).cells] == names
    for name in names:
        identity = json.loads((out / name / "experiment.json").read_text())
        assert identity["weight"] == float(name.split(",")[0].split("=")[1])
        assert identity["chairs"] == int(name[-1])
        rows = _rows(out / name)
        assert len(rows) == 4 and {r["method"] for r in rows} == {"grop", "llm-grop"}
        assert (out / name / "summary.md").exists()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["axes"] == ["weight", "chairs"]
    assert [c["name"] for c in summary["cells"]] == names
    assert summary["cells"][3]["axes"] == {"weight": "40.5", "chairs": "2"}
    assert {m["method"] for m in summary["cells"][0]["methods"]} == {"grop", "llm-grop"}
    assert summary["cells"][0]["paired"]["rating"][0]["n"] == 2
    table = (out / "summary.md").read_text()
    assert "| weight | chairs | method |" in table and table.count("| 40.5 | 2 |") == 2
    assert (out / "fig_sweep.png").read_bytes()[:4] == b"\x89PNG"


def test_a_cell_is_the_bench_it_names(swept: tuple[Path, Path], tmp_path: Path) -> None:
    _, out = swept
    bench = tmp_path / "bench"
    assert main(["bench", "--tasks", "1", "--methods", "grop,llm-grop", "--trials", "2",
                 "--no-images", "--llm", "replay", "--replay", str(RECORDING), "--weight",
                 "40.5", "--chairs", "2", "--out", str(bench), "-q"]) == 0
    assert _rows(bench) == _rows(out / "weight=40.5,chairs=2")


def test_rerun_resumes_and_a_new_value_adds_cells(swept: tuple[Path, Path],
                                                   tmp_path: Path, capsys) -> None:
    path, out = swept
    before = (out / "weight=20,chairs=0" / "trials.jsonl").read_bytes()
    assert main(["sweep", str(path), "--out", str(out)]) == 0
    assert "0 trial(s) run, 16 already done" in capsys.readouterr().out
    assert (out / "weight=20,chairs=0" / "trials.jsonl").read_bytes() == before
    wider = tmp_path / "wider.yaml"
    wider.write_text(SWEEP.replace("[0, 2]", "[0, 2, 3]"))
    assert main(["sweep", str(wider), "--out", str(out)]) == 0
    assert "8 trial(s) run, 16 already done" in capsys.readouterr().out


def test_a_cell_holding_another_experiment_is_refused(swept: tuple[Path, Path],
                                                      tmp_path: Path, capsys) -> None:
    _, out = swept
    other = tmp_path / "other.yaml"
    other.write_text(SWEEP.replace("images: false", "images: false\nfidelity_weight: 2"))
    assert main(["sweep", str(other), "--out", str(out)]) == 2
    assert ("weight=20,chairs=0: holds another experiment's results (different "
            "fidelity_weight)") in _one_line_error(capsys)


def test_a_directory_of_something_else_is_refused(tmp_path: Path, capsys) -> None:
    (tmp_path / "sweep.yaml").write_text(SWEEP)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "notes.txt").write_text("mine")
    assert main(["sweep", str(tmp_path / "sweep.yaml"), "--out", str(tmp_path / "out")]) == 2
    assert "not empty and holds no sweep.json" in _one_line_error(capsys)


def test_two_sweeps_at_once_on_one_directory(tmp_path: Path, capsys) -> None:
    first_file, second_file = tmp_path / "first.yaml", tmp_path / "second.yaml"
    first_file.write_text(SWEEP.replace("trials: 2", "trials: 4"))  # 32 trials, seconds
    second_file.write_text(SWEEP.replace("chairs: [0, 2]", "chairs: [1]"))
    out = tmp_path / "out"
    first = subprocess.Popen([sys.executable, "-m", "llm_grop", "sweep", str(first_file),
                              "--out", str(out), "-q", "--workers", "1"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while not (out / "sweep.json").exists():
        assert first.poll() is None and time.monotonic() < deadline
        time.sleep(0.02)
    # The first holds its directory from before its marker is written to after its last
    # report: a second sweep, and a bench, on it are refused at once, naming it.
    in_use = (f"llm-grop: error: --out {out}: in use by another llm-grop run on this "
              f"directory (pid {first.pid}); wait for it to end or stop it")
    assert main(["sweep", str(second_file), "--out", str(out), "-q"]) == 2
    assert _one_line_error(capsys) == in_use
    assert main(["bench", "--tasks", "1", "--trials", "1", "--llm", "replay", "--replay",
                 str(RECORDING), "--no-images", "-q", "--out", str(out)]) == 2
    assert _one_line_error(capsys) == in_use
    assert first.poll() is None
    _, err = first.communicate(timeout=300)
    assert first.returncode == 0, err
    names = [c.name for c in load_sweep(first_file).cells]
    assert [c["name"] for c in json.loads((out / "sweep.json").read_text())["cells"]] == names
    assert [c["name"] for c in json.loads((out / "summary.json").read_text())["cells"]] == names
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == sorted(names)
    # Once it has ended, the directory is free.
    assert main(["sweep", str(second_file), "--out", str(out), "-q"]) == 0
    assert (out / "weight=40.5,chairs=1" / "summary.md").exists()


@pytest.mark.parametrize(("text", "needle"), [
    (SWEEP.replace("trials: 2", "trials: two"),
     "s.yaml: trials: expected a whole number, got 'two'"),
    (SWEEP.replace("trials: 2", "trails: 2"), "s.yaml: trails: unknown key; did you mean "
                                              "'trials'?"),
    (SWEEP.replace("chairs: [0, 2]", "chairs: [0, -2]"),
     "s.yaml: grid.chairs[1]: must be at least 0, got -2"),
    (SWEEP.replace("chairs: [0, 2]", "chairs: []"), "s.yaml: grid.chairs: must not be empty"),
    (SWEEP.replace("chairs: [0, 2]", "colour: [red]"),
     "s.yaml: grid.colour: unknown key; expected one of tasks, methods, trials, images, llm, "
     "seed, method_options, task_files, catalog_files, scene, chairs, table, diners, "
     "capacity, m, "),
    (SWEEP.replace("trials: 2", "trials: 2\nchairs: 1"),
     "s.yaml: chairs: both in grid and at the top level; give it in one place"),
    (SWEEP.replace("backend: replay", "backend: replay, temprature: 0.5"),
     "s.yaml: llm.temprature: unknown key; did you mean 'temperature'?"),
    (SWEEP.replace("methods: grop,llm-grop\n", "").replace(
        "chairs: [0, 2]", "methods: [grop, 'grop,magic']"),
     "s.yaml: cell weight=20,methods=grop_magic: methods: unknown method 'magic'"),
    (SWEEP.replace("chairs: [0, 2]", "table: [scene, 12x8]"),
     "s.yaml: cell weight=20,table=12x8: table: 12 x 8 m is not a dining table"),
    (SWEEP.replace("chairs: [0, 2]", "fidelity_weight: [.inf]"),
     "s.yaml: grid.fidelity_weight[0]: expected a finite number, got inf"),
    (SWEEP.replace("chairs: [0, 2]", "simulator: [gazebo]"),
     "s.yaml: cell weight=20,simulator=gazebo: simulator: unknown simulator 'gazebo'"),
    (SWEEP.replace(str(RECORDING), "missing.jsonl"), "missing.jsonl: replay file not found"),
    (SWEEP.replace(f"llm: {{backend: replay, replay: {RECORDING}}}\n", "").replace(
        "chairs: [0, 2]", "llm: [{backend: replay, replay: a.jsonl}, "
                          "{backend: replay, replay: b.jsonl}]"),
     "grid: two cells would share the directory 'weight=20,llm=replay'"),
    (SWEEP.replace("chairs: [0, 2]", "table: [1.8x0.9m, 1.8X0.9m]"),
     "grid: two cells would share the directory 'weight=20,table=1.8X0.9m'"),
    (SWEEP.replace("chairs: [0, 2]", "chairs:"),
     "s.yaml: grid.chairs: no values; give a list, or leave the key out"),
    ("grid: [1, 2]\n", "s.yaml: grid: expected an object"),
    ("- tasks: 1\n", "s.yaml: top level: expected a mapping"),
    ("tasks: [1\n", "s.yaml line 2: not valid YAML"),
])
def test_a_malformed_sweep_file_is_one_line_naming_the_field(
        tmp_path: Path, capsys, text: str, needle: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    assert main(["sweep", str(path), "--out", str(tmp_path / "out")]) == 2
    assert needle in _one_line_error(capsys)
    assert not (tmp_path / "out").exists()


#: Mistakes in a sweep file and the exact line each gives (the file's path before it).
EXACT = [
    # An int where text is expected.
    ("simulator: 1\n", "simulator: expected text, got 1"),
    ("llm: {backend: replay, model: 7}\n", "llm.model: expected text, got 7"),
    # One value that is neither of a list's forms, and a list where one value goes.
    ("tasks: 1.5\n", "tasks: expected text or a list, got 1.5"),
    ("grid: {tasks: [1, true]}\n", "grid.tasks[1]: expected text or a list, got True"),
    ("tasks: [1, x]\n", "tasks[1]: expected a whole number, got 'x'"),
    ("chairs: [0, 4]\n", "chairs: one value here, not a list; to run each value, put chairs "
                         "under grid"),
    # Misspelt keys: at the top level, in grid, in an llm entry of the grid.
    ("trails: 2\n", "trails: unknown key; did you mean 'trials'?"),
    ("grid: {chiars: [0, 4]}\n", "grid.chiars: unknown key; did you mean 'chairs'?"),
    ("grid: {llm: [{backend: replay}, {backend: openai, modle: m}]}\n",
     "grid.llm[1].modle: unknown key; did you mean 'model'?"),
    ("grid: {llm: {backend: openai, modle: m}}\n",
     "grid.llm.modle: unknown key; did you mean 'model'?"),
]


@pytest.mark.parametrize(("text", "message"), EXACT)
def test_each_mistake_is_one_exact_line(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    with pytest.raises(BadInput) as info:
        load_sweep(path)
    assert str(info.value) == f"{path}: {message}"


def test_the_command_line_says_it_in_one_line_exit_2(tmp_path: Path, capsys) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(SWEEP.replace("chairs: [0, 2]", "chiars: [0, 2]"))
    assert main(["sweep", str(path), "--out", str(tmp_path / "out")]) == 2
    assert _one_line_error(capsys) == (f"llm-grop: error: {path}: grid.chiars: unknown key; "
                                       "did you mean 'chairs'?")


def test_one_value_is_a_list_of_one(tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    path.write_text("tasks: 1\nmethods: grop\ngrid: {chairs: 4, weight: [20, 40]}\n")
    sweep = load_sweep(path)
    assert [c.name for c in sweep.cells] == ["chairs=4,weight=20", "chairs=4,weight=40"]
    assert [(c.values.tasks, c.values.chairs) for c in sweep.cells] == [([1], 4), ([1], 4)]
    path.write_text("grid: {tasks: [1, [2, 3], paper], llm: {backend: replay, name: r}}\n")
    sweep = load_sweep(path)
    assert [c.name for c in sweep.cells] == ["tasks=1,llm=r", "tasks=2+3,llm=r",
                                             "tasks=paper,llm=r"]
    assert [c.values.tasks for c in sweep.cells] == [[1], [2, 3], "paper"]


def test_a_missing_sweep_file_is_one_line(tmp_path: Path, capsys) -> None:
    assert main(["sweep", str(tmp_path / "none.yaml"), "--out", str(tmp_path / "o")]) == 2
    assert "none.yaml: sweep file not found" in _one_line_error(capsys)


def test_paths_are_relative_to_the_sweep_file(tmp_path: Path) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "calls.jsonl").write_bytes(RECORDING.read_bytes())
    path = tmp_path / "sub" / "s.yaml"
    path.write_text(SWEEP.replace(str(RECORDING), "calls.jsonl").replace(
        "chairs: [0, 2]", "chairs: [0]").replace("[20, 40.5]", "[20]"))
    assert main(["sweep", str(path), "--out", str(tmp_path / "out"), "-q"]) == 0
    assert len(_rows(tmp_path / "out" / "weight=20,chairs=0")) == 4


def test_minus_v_logs_each_trial(tmp_path: Path, capsys) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(SWEEP.replace("chairs: [0, 2]", "chairs: [0]").replace("[20, 40.5]",
                                                                          "[20]"))
    assert main(["sweep", str(path), "--out", str(tmp_path / "out"), "-q", "-v"]) == 0
    assert "task 1 trial 1 llm-grop: rating" in capsys.readouterr().err
