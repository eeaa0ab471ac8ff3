"""The package's layers: no import cycles, and none of the arrows that must never exist.

Every import counts, at module level or inside a function, and so do
``importlib.import_module`` calls with a literal name. A package here is a subpackage of
``llm_grop`` (``planning``) or a top-level module (``api``, ``errors``).
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "llm_grop"

#: What each package may never import (the architecture's forbidden arrows).
FORBIDDEN: dict[str, set[str]] = {
    "world": {"*"},  # representation only: nothing but errors
    "geometry": {"*"},  # below planning and simulation: nothing but world and errors
    "llm": {"world", "language", "arrangement", "planning", "simulation", "methods",
            "evaluation", "experiment", "render", "api", "cli", "ratings"},
    # Reading people's words sits below arrangement and evaluation, which both read
    # through it; it never reaches up into them.
    "language": {"arrangement", "evaluation", "planning", "simulation", "methods",
                 "experiment", "render", "api", "cli", "ratings", "env", "geometry"},
    "arrangement": {"evaluation", "experiment", "planning", "simulation", "methods", "api",
                    "cli", "render", "ratings"},
    "planning": {"evaluation", "experiment", "simulation", "methods", "api", "cli", "render",
                 "ratings", "execution"},
    "simulation": {"evaluation", "experiment", "planning", "methods", "api", "cli", "render",
                   "ratings", "execution"},
    # The executive runs plans on simulators' primitives: it reads plans, never makes them.
    "execution": {"evaluation", "experiment", "planning", "methods", "api", "cli", "render",
                  "ratings", "arrangement", "language", "llm", "env"},
    "methods": {"evaluation", "experiment", "api", "cli", "render", "ratings"},
    "evaluation": {"api", "experiment", "arrangement", "planning", "simulation", "methods",
                   "llm", "render", "cli", "ratings"},
    "render": {"evaluation", "experiment", "api", "cli", "arrangement", "planning",
               "simulation", "methods", "llm", "ratings"},
    "api": {"experiment", "cli", "evaluation", "render", "ratings"},
    "experiment": {"cli", "ratings"},
    "env": {"evaluation", "experiment", "api", "cli", "methods", "ratings"},
    # The human study sits beside the bench: it reads results, never runs a pipeline.
    "ratings": {"cli", "api", "llm", "arrangement", "planning", "simulation", "methods",
                "env", "render", "service"},
    # The service calls the public API as the CLI does; it never rates, sweeps or studies.
    "service": {"cli", "evaluation", "experiment", "ratings", "env"},
    # The doctor must run when parts are broken: it checks them from outside and loads
    # none of the pipeline.
    "doctor": {"api", "cli", "world", "geometry", "language", "arrangement", "planning",
               "methods", "evaluation", "experiment", "execution", "render", "env", "ratings",
               "service"},
}
#: What a package marked ``*`` may still import.
ALLOWED_BELOW = {"world": {"errors"}, "geometry": {"errors", "world"}}
#: Packages the rater's knowledge must never reach, not even by name.
PLANNING = ("arrangement", "planning", "methods", "simulation", "geometry")


def imported_modules(path: Path, root: Path) -> list[str]:
    """Absolute names of every module ``path`` imports (``root`` holds ``llm_grop``)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    parts = path.relative_to(root).with_suffix("").parts
    package = ".".join(parts if parts[-1] == "__init__" else parts[:-1]).removesuffix(
        ".__init__")
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{parent}.{base}" if base else parent
            # `from llm_grop import seeds` imports the module, not the package's facade.
            out += ([] if base == "llm_grop" else [base]) + [f"{base}.{a.name}"
                                                              for a in node.names]
        elif isinstance(node, ast.Call) and node.args \
                and isinstance(node.args[0], ast.Constant) \
                and getattr(node.func, "attr", getattr(node.func, "id", "")) in (
                    "import_module", "__import__"):
            out.append(str(node.args[0].value))
    return out


def package_of(module: str, root: Path) -> str | None:
    """The package a dotted module name belongs to, or ``None`` outside ``llm_grop``."""
    parts = module.split(".")
    if parts[0] != "llm_grop":
        return None
    if len(parts) == 1:
        return "llm_grop"
    name = parts[1]
    exists = (root / "llm_grop" / name).is_dir() or (root / "llm_grop" / f"{name}.py").is_file()
    return name if exists else "llm_grop"


def package_graph(root: Path) -> dict[str, set[str]]:
    """``package -> packages it imports`` for the tree under ``root/llm_grop``."""
    graph: dict[str, set[str]] = defaultdict(set)
    for path in sorted((root / "llm_grop").rglob("*.py")):
        rel = path.relative_to(root / "llm_grop").parts
        source = "llm_grop" if rel == ("__init__.py",) else rel[0].removesuffix(".py")
        graph[source]
        for module in imported_modules(path, root):
            target = package_of(module, root)
            if target is not None and target != source:
                graph[source].add(target)
    return dict(graph)


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every strongly connected set of more than one package (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def violations(graph: dict[str, set[str]]) -> list[str]:
    """The forbidden arrows present in ``graph``."""
    out = []
    for source, targets in sorted(graph.items()):
        banned = FORBIDDEN.get(source, set())
        for target in sorted(targets):
            if "*" in banned and target not in ALLOWED_BELOW[source] \
                    or target in banned:
                out.append(f"{source} -> {target}")
    return out


def test_there_are_no_import_cycles_between_packages() -> None:
    graph = package_graph(SRC.parent)
    assert {"world", "planning", "simulation", "evaluation", "experiment"} <= set(graph)
    assert cycles(graph) == []


def test_no_forbidden_arrow_exists() -> None:
    assert violations(package_graph(SRC.parent)) == []


def test_planning_code_never_names_the_rater() -> None:
    offenders = []
    for pkg in PLANNING:
        for path in (SRC / pkg).rglob("*"):
            if path.is_file() and "__pycache__" not in path.parts:
                text = path.read_text(encoding="utf-8", errors="replace")
                if "conventions.yaml" in text or "llm_grop.evaluation" in text:
                    offenders.append(str(path))
    assert offenders == []


@pytest.mark.parametrize("source", [
    "from llm_grop.evaluation.rater import rate\n",
    "import llm_grop.evaluation\n",
    "from llm_grop import evaluation\n",
    "def f():\n    from ...evaluation import rules\n",
    "import importlib\nimportlib.import_module('llm_grop.evaluation')\n",
])
def test_the_scan_catches_a_forbidden_import(source: str, tmp_path: Path) -> None:
    pkg = tmp_path / "llm_grop" / "planning" / "sub"
    pkg.mkdir(parents=True)
    (tmp_path / "llm_grop" / "evaluation").mkdir()
    (pkg / "x.py").write_text(source)
    assert violations(package_graph(tmp_path)) == ["planning -> evaluation"]


def test_the_scan_catches_a_cycle(tmp_path: Path) -> None:
    for name, other in (("world", "render"), ("render", "world")):
        (tmp_path / "llm_grop" / name).mkdir(parents=True, exist_ok=True)
        (tmp_path / "llm_grop" / name / "m.py").write_text(f"import llm_grop.{other}.m\n")
    assert cycles(package_graph(tmp_path)) == [["render", "world"]]
