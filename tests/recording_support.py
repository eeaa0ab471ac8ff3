"""What the recording tests share: reading a Rerun recording back with Rerun's own reader
(``rerun.chunk.RrdReader``) and its command line (``rerun rrd verify``), with Rerun's
analytics switched off in a configuration of the test's own."""

from __future__ import annotations

import os
import subprocess
from collections import defaultdict
from pathlib import Path
from typing import Any

import pytest

RECORDING = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "embedded_calls.jsonl"
#: The embedded model's recorded answers, replayed.
REPLAY = ["--llm", "replay", "--replay", str(RECORDING)]


def rerun_env(tmp: Path) -> dict[str, str]:
    """The environment for Rerun's programs: its configuration in ``tmp`` with analytics
    off (a test sends nothing anywhere), no display."""
    from llm_grop.cli.view import rerun_binary

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["XDG_CONFIG_HOME"] = str(tmp / "rerun-config")
    subprocess.run([str(rerun_binary()), "analytics", "disable"], env=env, check=True,
                   capture_output=True, timeout=60)
    return env


def verify(path: Path, tmp: Path) -> None:
    """``rerun rrd verify``: the recording loads and every column is understood."""
    from llm_grop.cli.view import rerun_binary

    done = subprocess.run([str(rerun_binary()), "rrd", "verify", str(path)],
                          env=rerun_env(tmp), capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr


class Recording:
    """A recording read back: its chunks' columns by entity path (as Rerun writes them,
    spaces escaped: ``/world/objects/dinner\\ plate``)."""

    def __init__(self, path: Path) -> None:
        reader = pytest.importorskip("rerun.chunk").RrdReader(str(path))
        self.columns: dict[str, dict[str, list[Any]]] = defaultdict(lambda: defaultdict(list))
        self.static: set[str] = set()
        for chunk in reader.store().stream():
            batch = chunk.to_record_batch()
            if chunk.is_static:
                self.static.add(chunk.entity_path)
            for name in batch.schema.names:
                column = batch.column(name)
                if name in ("sim_time", "log_time"):  # nanoseconds
                    column = column.cast("int64")
                self.columns[chunk.entity_path][name] += column.to_pylist()

    @property
    def entities(self) -> set[str]:
        return set(self.columns)

    def times(self, entity: str) -> list[float]:
        """The ``sim_time`` of each row of ``entity``, seconds."""
        return [t / 1e9 for t in self.columns[entity]["sim_time"]]

    def column(self, entity: str, name: str) -> list[Any]:
        return self.columns[entity][name]


def entity(*parts: str) -> str:
    """The entity path Rerun stores for ``parts`` (a space escaped)."""
    return "/" + "/".join(p.replace(" ", "\\ ") for p in parts)


def run_without_package(package: str, args: list[str]) -> subprocess.CompletedProcess[str]:
    """``llm-grop ARGS`` in a fresh Python where importing ``package`` fails, as where its
    optional extra is not installed."""
    import sys

    code = (f"import sys; sys.modules[{package!r}] = None; from llm_grop.cli import main; "
            f"sys.exit(main({args!r}))")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)

