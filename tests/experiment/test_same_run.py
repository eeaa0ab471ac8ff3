"""Same inputs, same run, wherever it runs: a bench trial is the run ``llm-grop run`` gives
with the same settings (every method, both simulators), whatever trials its process ran
before, in a fresh process, and on a CPU starved by busy competitors.

Every LLM answer is replayed from the embedded model's recording, so this is offline.
"""

from __future__ import annotations

import json
import os
import random
import subprocess
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import pytest

import llm_grop
from llm_grop.api import run
from llm_grop.cli import main
from llm_grop.contract.run_json import run_to_dict
from llm_grop.experiment.trial import (
    RUN_DEPENDENT_FIELDS,
    TIMING_FIELDS,
    TrialRunner,
    TrialSettings,
    TrialSpec,
)
from llm_grop.planning.navigation import Navigator
from scenes import doorway_room

RECORDING = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "embedded_calls.jsonl"
SETTINGS = TrialSettings.of(llm="replay", replay=str(RECORDING))
METHODS = ("tpra", "latp", "grop", "llm-grop")
#: 2D trials: every method on a three- and a five-object task, trials 0 and 1 (seed = trial).
SPECS = tuple(TrialSpec(m, task, k, k) for task in (1, 8) for k in (0, 1) for m in METHODS)
#: A one-object task, so that MuJoCo's episodes stay short.
ONE_OBJECT = "tasks:\n  - id: 9\n    objects: [dinner plate]\n"

#: Runs trials (given as JSON ``[method, task, trial, seed]`` lists) and the doorway path in
#: a fresh process and prints ``{"rows": [...], "path": [...]}``. Given a CPU to starve on,
#: it first runs one trial (so everything is imported and loaded), then pins itself to CPU,
#: takes the lowest priority, says ``ready`` and waits for a line on stdin (the
#: competitors are started meanwhile) before its real work.
CHILD = """
import json, os, sys
sys.path[:0] = [sys.argv[1], os.path.dirname(sys.argv[1])]
from test_same_run import SETTINGS, TrialRunner, TrialSpec, doorway_path
args = json.loads(sys.argv[2])
runner = TrialRunner(SETTINGS)
if args["starve"] is not None:
    runner(TrialSpec("tpra", 1, 0, 0))
    os.sched_setaffinity(0, {args["starve"]})
    os.nice(19)
    print("ready", flush=True)
    sys.stdin.readline()
rows = [runner(TrialSpec(*s)).to_json() for s in args["specs"]]
print(json.dumps({"rows": rows, "path": doorway_path() if args["doorway"] else []}))
"""

#: A process that burns one CPU until it is killed. At niceness 5 against the starved
#: process's 19 it takes about 96 % of the CPU (weights 335 and 15): the starved process
#: runs some 20 times slower on an idle machine, so that the doorway path (about 40 ms of
#: CPU) takes more wall time than the half second at which OMPL's clock used to end it.
BUSY = ("import os, sys\nos.sched_setaffinity(0, {int(sys.argv[1])})\nos.nice(5)\n"
        "while True:\n    pass\n")


def stable(row: dict[str, Any]) -> dict[str, Any]:
    """A trial row (as JSON) without the fields that depend on how the experiment ran."""
    return {k: v for k, v in row.items() if k not in RUN_DEPENDENT_FIELDS}


def assert_same_run(run_json: dict[str, Any], row: dict[str, Any]) -> None:
    """``row``, a bench trial's, repeats ``run_json``, ``run --json``'s, apart from its
    wall-clock times; the row counts the LLM's calls where the run JSON lists them."""
    run_json = json.loads(json.dumps(run_json))
    log = run_json["planned"].get("llm", {}).pop("log", [])
    assert (row["llm_calls"], row["llm_prompt_tokens"], row["llm_completion_tokens"]) == (
        len(log), sum(c.get("prompt_tokens") or 0 for c in log),
        sum(c.get("completion_tokens") or 0 for c in log))
    for key in TIMING_FIELDS:
        run_json.pop(key, None)
    assert run_json.keys() <= row.keys()
    assert {k: row[k] for k in run_json} == run_json


def doorway_path() -> list[list[float]]:
    """A path through a 0.74 m doorway for the 0.6 m base, which keeps its 6 cm margin only
    just: with this seed RRTConnect needs about 8,000 iterations (some 40 ms of CPU)."""
    path = Navigator(doorway_room(0.74), 0.3).plan((1.0, 0.6), (5.0, 3.2), seed=8)
    return [list(p) for p in path] if path is not None else []


def _child(specs: Sequence[TrialSpec], hash_seed: int, *, starve: int | None = None,
           doorway: bool = False) -> subprocess.Popen[str]:
    """:data:`CHILD` started in a fresh process with ``PYTHONHASHSEED=hash_seed``."""
    env = os.environ | {"PYTHONHASHSEED": str(hash_seed), "PYTHONPATH": os.pathsep.join(
        [str(Path(llm_grop.__file__).parents[1]), os.environ.get("PYTHONPATH", "")])}
    args = {"specs": [[s.method, s.task, s.trial, s.seed] for s in specs], "starve": starve,
            "doorway": doorway}
    return subprocess.Popen([sys.executable, "-c", CHILD, str(Path(__file__).parent),
                             json.dumps(args)], env=env, text=True, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE)


def _output(proc: subprocess.Popen[str]) -> dict[str, Any]:
    out, _ = proc.communicate(timeout=600)
    assert proc.returncode == 0
    return json.loads(out.splitlines()[-1])


@pytest.fixture(scope="module")
def rows() -> dict[TrialSpec, dict[str, Any]]:
    """Each of :data:`SPECS` run in this process by one runner, in order, as a bench
    worker runs them."""
    runner = TrialRunner(SETTINGS)
    return {s: runner(s).to_json() for s in SPECS}


# -- a bench trial is the run -----------------------------------------------------------------

@pytest.mark.parametrize("method", METHODS)
def test_a_trial_is_the_run_with_the_same_settings(rows, method: str) -> None:
    for spec in (s for s in SPECS if s.method == method):
        # The trial's own settings record, with the trial's task, method and seed.
        result = run(settings=SETTINGS.run, task=spec.task, method=method, seed=spec.seed)
        assert_same_run(run_to_dict(result), rows[spec])


def test_a_mujoco_trial_is_the_run_with_the_same_settings(tmp_path: Path) -> None:
    task_file = tmp_path / "one.yaml"
    task_file.write_text(ONE_OBJECT)
    # One runner, as a worker has: each episode after the first reuses its simulator.
    mujoco = SETTINGS.run.with_values(simulator="mujoco", task_files=(str(task_file),))
    runner = TrialRunner(TrialSettings(mujoco))
    for method in METHODS:
        row = runner(TrialSpec(method, 9, 0, 0)).to_json()
        assert row["simulator"] == "mujoco" and row["status"] == "ok"
        result = run(settings=mujoco, task=9, method=method, seed=0)
        assert_same_run(run_to_dict(result), row)


def test_the_cli_bench_trial_is_the_cli_run(rows, tmp_path: Path) -> None:
    replay = ["--llm", "replay", "--replay", str(RECORDING)]
    out = tmp_path / "bench"
    assert main(["bench", "--tasks", "8", "--trials", "2", "--methods", "llm-grop", *replay,
                 "--no-images", "--out", str(out), "-q"]) == 0
    bench = [json.loads(line) for line in (out / "trials.jsonl").read_text().splitlines()]
    # The CLI's defaults are the Python API's.
    assert [stable(r) for r in bench] == [stable(rows[TrialSpec("llm-grop", 8, k, k)])
                                          for k in (0, 1)]
    path = tmp_path / "run.json"
    # Trial k has seed seed + k: trial 1 of a bench from seed 0 is the run with seed 1.
    assert main(["run", "--task", "8", "--method", "llm-grop", "--seed", "1", *replay,
                 "--json", str(path), "-q"]) == 0
    assert_same_run(json.loads(path.read_text()), bench[1])


# -- whatever ran before, in any process --------------------------------------------------------

def test_another_order_in_the_same_process_gives_the_same_rows(rows) -> None:
    runner = TrialRunner(SETTINGS)
    again = {s: runner(s).to_json() for s in reversed(SPECS)}
    assert {s: stable(r) for s, r in again.items()} == {s: stable(r) for s, r in rows.items()}


def test_fresh_processes_give_the_same_rows(rows) -> None:
    order = list(SPECS)
    random.Random(36).shuffle(order)
    # Each process has its own string hashing, so set order cannot leak into a row.
    halves = [_child(order[:8], 1), _child(order[8:], 2)]
    got = [row for proc in halves for row in _output(proc)["rows"]]
    assert [stable(r) for r in got] == [stable(rows[s]) for s in order]


# -- a starved CPU ------------------------------------------------------------------------------

#: The trial the starved process runs: a short one, with three paths that bend.
STARVED = (TrialSpec("grop", 1, 1, 1),)


@pytest.fixture(scope="module")
def starved() -> Iterator[dict[str, Any]]:
    """:data:`STARVED` and :func:`doorway_path` in a fresh process at the lowest priority,
    pinned to one CPU that a busy process (:data:`BUSY`) shares with it."""
    cpu = min(os.sched_getaffinity(0))
    child = _child(STARVED, 3, starve=cpu, doorway=True)
    busy: list[subprocess.Popen[bytes]] = []
    try:
        assert child.stdout is not None and child.stdin is not None
        assert child.stdout.readline().strip() == "ready"
        busy = [subprocess.Popen([sys.executable, "-c", BUSY, str(cpu)])]
        child.stdin.write("go\n")
        child.stdin.flush()
        yield _output(child)
    finally:
        for proc in [*busy, child]:
            proc.kill()
            proc.wait()


def test_a_starved_planner_gives_the_same_rows(rows, starved) -> None:
    assert [stable(r) for r in starved["rows"]] == [stable(rows[s]) for s in STARVED]


def test_a_starved_planner_finds_the_same_paths(starved) -> None:
    expected = doorway_path()
    assert expected and json.loads(json.dumps(expected)) == starved["path"]
