"""The package's layers as a contract: import-linter checks ``.importlinter``'s contracts.

Every subpackage and top-level module of ``llm_grop`` sits in one layer and imports only
the layers below it, and none of the architecture's forbidden arrows exists, directly or
through other modules (import-linter follows every chain of imports, at module level,
inside functions and under ``TYPE_CHECKING``).
"""

from __future__ import annotations

import configparser
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "llm_grop"
CONFIG = ROOT / ".importlinter"
#: What the rating site must never load, not even through another module.
PIPELINE = ("api", "planning", "simulation", "methods")
#: Packages the rater's knowledge must never reach, not even by name.
PLANNING = ("arrangement", "planning", "methods", "simulation", "geometry")


def contracts(path: Path = CONFIG) -> dict[str, configparser.SectionProxy]:
    """The contracts of the import-linter file ``path``, by their section's id."""
    parser = configparser.ConfigParser()
    parser.read(path, encoding="utf-8")
    prefix = "importlinter:contract:"
    return {s.removeprefix(prefix): parser[s] for s in parser.sections()
            if s.startswith(prefix)}


def layered(path: Path = CONFIG) -> list[str]:
    """The modules that the layers contract of ``path`` places, top layer first."""
    lines = contracts(path)["layers"]["layers"].split("\n")
    return [m.strip("() ") for line in lines for m in re.split(r"[|:]", line) if m.strip()]


def package_modules(src: Path = SRC) -> set[str]:
    """Every subpackage and top-level module of the package in ``src``."""
    return {p.name for p in src.iterdir() if (p / "__init__.py").is_file()} | {
        p.stem for p in src.glob("*.py") if p.name != "__init__.py"}


def lint(config: Path, path: Path = SRC.parent) -> tuple[int, str]:
    """import-linter's exit status and report for the contracts in ``config``, on the
    packages found first in ``path``. It runs in a process of its own: it configures
    logging for itself, which would silence the package's loggers in the tests after."""
    run = ("import sys; from importlinter.cli import lint_imports; "
           "sys.exit(lint_imports(config_filename=sys.argv[1], no_cache=True, no_logo=True))")
    paths = os.pathsep.join(filter(None, [str(path), os.environ.get("PYTHONPATH")]))
    done = subprocess.run([sys.executable, "-c", run, str(config)], capture_output=True,
                          text=True, env=os.environ | {"PYTHONPATH": paths})
    return done.returncode, done.stdout + done.stderr


def test_every_module_is_in_exactly_one_layer() -> None:
    placed = layered()
    assert len(placed) == len(set(placed))
    assert package_modules() - set(placed) == set(), "a module sits in no layer"
    assert set(placed) - package_modules() == set(), "a layer names no module"
    assert contracts()["layers"].getboolean("exhaustive")


def test_the_import_contracts_hold() -> None:
    code, report = lint(CONFIG)
    assert code == 0, report
    assert re.search(r"Contracts: \d+ kept, 0 broken", report), report


def test_every_contract_follows_indirect_imports() -> None:
    for name, contract in contracts().items():
        assert not contract.getboolean("allow_indirect_imports", False), name
    banned = contracts()["ratings"]["forbidden_modules"].split()
    assert {f"llm_grop.{p}" for p in PIPELINE} <= set(banned)


def test_a_forbidden_import_through_another_module_breaks_a_contract(tmp_path: Path) -> None:
    pkg = tmp_path / "layered_demo"
    for name, body in (("__init__", ""), ("site", "from layered_demo import harness\n"),
                       ("harness", "def f():\n    from layered_demo import pipeline\n"),
                       ("pipeline", "")):
        pkg.mkdir(exist_ok=True)
        (pkg / f"{name}.py").write_text(body)
    config = tmp_path / ".importlinter"
    config.write_text("[importlinter]\nroot_package = layered_demo\n\n"
                      "[importlinter:contract:site]\nname = site loads no pipeline\n"
                      "type = forbidden\nsource_modules = layered_demo.site\n"
                      "forbidden_modules = layered_demo.pipeline\n")
    code, report = lint(config, tmp_path)
    assert code == 1
    assert "layered_demo.site -> layered_demo.harness" in report
    assert "layered_demo.harness -> layered_demo.pipeline" in report


def test_the_rating_site_loads_no_pipeline() -> None:
    # What import-linter cannot see: a package's __init__ runs with any of its modules.
    code = ("import importlib, pkgutil, sys, llm_grop.ratings as r\n"
            "for m in pkgutil.iter_modules(r.__path__):\n"
            "    importlib.import_module('llm_grop.ratings.' + m.name)\n"
            "print(sorted(m for m in sys.modules if m.split('.')[:2] in\n"
            "             [['llm_grop', p] for p in sys.argv[1:]]))\n")
    done = subprocess.run([sys.executable, "-c", code, *PIPELINE], capture_output=True,
                          text=True, check=True)
    assert done.stdout.strip() == "[]"


def test_planning_code_never_names_the_rater() -> None:
    offenders = []
    for pkg in PLANNING:
        for path in (SRC / pkg).rglob("*"):
            if path.is_file() and "__pycache__" not in path.parts:
                text = path.read_text(encoding="utf-8", errors="replace")
                if "conventions.yaml" in text or "llm_grop.evaluation" in text:
                    offenders.append(str(path))
    assert offenders == []


def test_names_moved_down_a_layer_stay_importable_where_they_were() -> None:
    from llm_grop import figures
    from llm_grop.experiment import rows, runner
    from llm_grop.render import table

    assert (runner.ROWS, runner.read_rows) == (rows.ROWS, rows.read_rows)
    assert (table.BACKGROUND, table.DPI, table.STYLE, table.save_png) == (
        figures.BACKGROUND, figures.DPI, figures.STYLE, figures.save_png)
