"""A small real bench (2 tasks x 2 trials x 4 methods, replayed LLM) and studies of it."""

from __future__ import annotations

import importlib.util
import shutil
import sys
from pathlib import Path
from types import ModuleType

import pytest

from browser_support import screenshots  # noqa: F401 - a fixture for the browser test
from llm_grop.cli import main
from llm_grop.ratings.study import create_study, invite, items_from_bench

ROOT = Path(__file__).resolve().parents[2]
RECORDING = ROOT / "benchmarks" / "data" / "embedded_calls.jsonl"
ADMIN = "test-admin-token-0123456789"


def load_benchmark(name: str) -> ModuleType:
    """A script under benchmarks/ as a module (the load test shares its driver)."""
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def bench_dir(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("ratings") / "bench"
    assert main(["bench", "--tasks", "1,2", "--trials", "2", "--llm", "replay", "--replay",
                 str(RECORDING), "--out", str(out), "-q"]) == 0
    return out


@pytest.fixture(scope="session")
def bench_items(bench_dir: Path):
    return items_from_bench(bench_dir)


@pytest.fixture
def study(tmp_path: Path, bench_items) -> tuple[Path, list[str]]:
    """A fresh study of the bench with three raters: ``(database, invite codes)``."""
    db = tmp_path / "study.db"
    create_study(db, bench_items, name="test study", source="bench", seed=0)
    return db, invite(db, 3)


@pytest.fixture
def copy_of(tmp_path: Path):
    def copy(path: Path) -> Path:
        target = tmp_path / f"copy-{path.name}"
        shutil.copy(path, target)
        return target
    return copy
