"""Executors: every registered one gives the local rows; Ray on a real local cluster,
resumed after Ctrl-C or a kill; the local executor never imports Ray."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import jsonschema
import pytest

from llm_grop.cli import main
from llm_grop.contract.schemas import json_schema
from llm_grop.experiment.executors import EXECUTORS
from llm_grop.experiment.ray_loopback import LOOPBACK
from llm_grop.experiment.trial import RUN_DEPENDENT_FIELDS
from llm_grop.methods.base import ComposedMethod
from llm_grop.methods.registry import METHODS, register_method

RECORDING = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "embedded_calls.jsonl"
BASE = ["bench", "--tasks", "1,2", "--trials", "2", "--llm", "replay", "--replay",
        str(RECORDING), "-q"]
CLI = "import sys; from llm_grop.cli import main; sys.exit(main(sys.argv[1:]))"


def _rows(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "trials.jsonl").read_text().splitlines()]


def _stable(rows: list[dict]) -> list[dict]:
    return [{k: v for k, v in r.items() if k not in RUN_DEPENDENT_FIELDS} for r in rows]


@pytest.fixture(scope="module")
def local(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("local") / "bench"
    assert main(BASE + ["--out", str(out), "--workers", "2"]) == 0
    return out


@pytest.fixture(scope="module")
def ray_cluster():
    """A real Ray cluster on this machine, as `ray.init(num_cpus=2)` starts it, on 127.0.0.1."""
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, configure_logging=False,
             _node_ip_address=LOOPBACK)
    yield ray
    ray.shutdown()


@pytest.mark.parametrize("name", EXECUTORS.names())
def test_every_executor_gives_the_local_rows(name: str, local: Path, ray_cluster,
                                             tmp_path: Path) -> None:
    out = tmp_path / name
    assert main(BASE + ["--out", str(out), "--executor", name]) == 0
    rows = _rows(out)
    assert _stable(rows) == _stable(_rows(local))
    validator = jsonschema.Draft202012Validator(json_schema("trial"))
    for row in rows:
        validator.validate(row)
        # Pictures drawn by a worker, shipped back or not, are the same files.
        assert (out / row["image"]).read_bytes() == (local / row["image"]).read_bytes()


def test_ray_cluster_matches_local_two_tasks_two_trials(local: Path, ray_cluster,
                                                        tmp_path: Path) -> None:
    assert ray_cluster.cluster_resources()["CPU"] == 2
    out = tmp_path / "ray"
    assert main(BASE + ["--out", str(out), "--executor", "ray", "--no-images"]) == 0
    rows = _rows(out)
    assert len(rows) == 2 * 2 * 4
    want = [{k: v for k, v in r.items() if k != "image"} for r in _stable(_rows(local))]
    assert _stable(rows) == want


def _start(out: Path, *extra: str) -> subprocess.Popen:
    cmd = [sys.executable, "-c", CLI, *BASE, "--out", str(out), "--executor", "ray", *extra]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def _wait_for_rows(proc: subprocess.Popen, out: Path, count: int) -> None:
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline and proc.poll() is None:
        rows = out / "trials.jsonl"
        if rows.exists() and rows.read_text().count("\n") >= count:
            return
        time.sleep(0.05)


@pytest.mark.parametrize("how", [signal.SIGINT, signal.SIGKILL], ids=["ctrl-c", "killed"])
def test_interrupted_ray_run_resumes_with_no_trial_lost_or_duplicated(
        how: signal.Signals, local: Path, tmp_path: Path) -> None:
    out = tmp_path / "partial"
    proc = _start(out, "--workers", "1")
    _wait_for_rows(proc, out, 2)
    proc.send_signal(how)
    _, err = proc.communicate(timeout=120)
    if how == signal.SIGINT and proc.returncode == 130:
        assert b"rerun the same command to resume" in err and b"Traceback" not in err
    before = len(_rows(out))
    assert before >= 1
    assert main(BASE + ["--out", str(out), "--executor", "ray"]) == 0
    rows = _rows(out)
    keys = [(r["task"], r["trial"], r["method"]) for r in rows]
    assert len(keys) == len(set(keys)) == 16
    assert _stable(rows) == _stable(_rows(local))


def test_the_local_executor_never_imports_ray(tmp_path: Path) -> None:
    code = (f"import sys; from llm_grop.cli import main; "
            f"code = main({BASE + ['--out', str(tmp_path / 'x'), '--tasks', '1', '--trials', '1', '--methods', 'grop']!r}); "  # noqa: E501
            "sys.exit(code or ('ray' in sys.modules) * 9)")
    assert subprocess.run([sys.executable, "-c", code], timeout=300).returncode == 0


def test_ray_missing_is_one_line(tmp_path: Path) -> None:
    code = ("import sys; sys.modules['ray'] = None; " + CLI)
    proc = subprocess.run([sys.executable, "-c", code, *BASE, "--out", str(tmp_path / "x"),
                           "--executor", "ray"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2
    assert proc.stderr.strip() == ("llm-grop: error: --executor ray: Ray is not installed; "
                                   "install it with pip install 'llm-grop[ray]'")
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize(("extra", "needle"), [
    (["--executor", "dask"], "--executor: unknown executor 'dask' (available: local, ray"),
    (["--ray-address", "auto"], "--ray-address: only with --executor ray"),
    (["--cpus-per-trial", "0"], "--cpus-per-trial"),
    (["--llm-threads", "0"], "--llm-threads"),
])
def test_bad_execution_flags(tmp_path: Path, capsys, extra: list[str], needle: str) -> None:
    assert main(BASE + ["--out", str(tmp_path / "x")] + extra) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and "\n" not in err and "Traceback" not in err


def test_unreachable_ray_cluster_is_one_line(tmp_path: Path) -> None:
    # In a process of its own: this module's tests keep a cluster joined in theirs.
    proc = subprocess.run([sys.executable, "-c", CLI, *BASE, "--out", str(tmp_path / "x"),
                           "--executor", "ray", "--ray-address", "127.0.0.1:1"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2
    assert proc.stderr.startswith("llm-grop: error: --executor ray: cannot reach the Ray "
                                  "cluster at 127.0.0.1:1: nothing answers at 127.0.0.1:1")
    assert proc.stderr.count("\n") == 1


def test_a_failing_ray_task_is_one_line_naming_the_trial(ray_cluster, tmp_path: Path,
                                                         capsys) -> None:
    # A method registered from a module the Ray workers cannot import (this test module is
    # on the driver's path only), as a node without a plugin would be.
    register_method(NEEDS_A_MODULE)
    try:
        code = main(BASE + ["--out", str(tmp_path / "x"), "--executor", "ray", "--tasks", "1",
                            "--trials", "1", "--methods", "needs-a-module"])
    finally:
        METHODS.unregister("needs-a-module")
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert code == 2, err
    assert err.startswith("llm-grop: error: task 1 trial 0 needs-a-module: a Ray worker could "
                          "not run it: ")
    assert "No module named 'test_executors'" in err
    assert err.endswith("(every node needs llm-grop, its plugins and the experiment's files)")


class _Here(ComposedMethod):
    """A method whose class lives in this test module."""


NEEDS_A_MODULE = _Here("needs-a-module", "random arrangement", uses_llm=False,
                       standing="utility", best_of_all=True)
