"""A small real bench (2 tasks x 2 trials x 4 methods, replayed LLM) and studies of it."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from browser_support import screenshots  # noqa: F401 - a fixture for the browser test
from llm_grop.cli import main
from llm_grop.ratings.study import create_study, invite, items_from_bench
from ratings_support import ADMIN, RECORDING, load_benchmark  # noqa: F401


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
