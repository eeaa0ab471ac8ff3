"""The package's shape: its import graph between packages, the layer contract's result, and
its largest modules.

Prints every arrow ``package -> packages it imports`` (grimp's graph, the one import-linter
checks), then import-linter's report on the contracts in ``.importlinter`` (the layers and
the arrows that must never exist, followed through every chain of imports; a broken
contract lists the chains it found), and the modules with the most lines. Its exit status
is import-linter's: 0 when every contract is kept.

Run: .venv/bin/python benchmarks/layers.py [--largest 10] [--config .importlinter] [--quick]
"""

from __future__ import annotations

import argparse
import sys
from collections import defaultdict
from pathlib import Path

import grimp
from common import parse_args
from importlinter.cli import lint_imports

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "llm_grop"


def package_graph() -> dict[str, set[str]]:
    """``package -> packages it imports`` between the children of ``llm_grop``."""
    graph = grimp.build_graph("llm_grop")
    out: dict[str, set[str]] = defaultdict(set)
    for module in graph.modules:
        source = module.split(".")[1] if "." in module else "llm_grop"
        out[source]
        for target in graph.find_modules_directly_imported_by(module):
            name = target.split(".")[1] if "." in target else "llm_grop"
            if name != source:
                out[source].add(name)
    return dict(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--largest", type=int, default=10, help="How many modules to list.")
    ap.add_argument("--config", type=Path, default=ROOT / ".importlinter",
                    help="The import-linter contracts to check.")
    args = parse_args(ap, {"largest": 3})
    sys.path.insert(0, str(SRC.parent))  # this checkout's package, whatever is installed
    graph = package_graph()
    print("Import graph between packages:")
    for source in sorted(graph):
        print(f"  {source} -> {', '.join(sorted(graph[source])) or '(nothing)'}")
    print("Layer contract (import-linter):", flush=True)
    code = lint_imports(config_filename=str(args.config), no_cache=True, no_logo=True)
    sizes = sorted(((len(p.read_text(encoding='utf-8').splitlines()), p.relative_to(SRC))
                    for p in SRC.rglob("*.py")), reverse=True)
    print(f"Largest modules ({len(sizes)} in all):")
    for lines, path in sizes[:args.largest]:
        print(f"  {lines:4d}  {path}")
    return code


if __name__ == "__main__":
    sys.exit(main())
