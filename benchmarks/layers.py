"""The package's shape: its import graph between packages, and its largest modules.

Prints every arrow ``package -> packages it imports`` (the same scan as
``tests/test_layers.py``, which fails on a cycle or a forbidden arrow) and the modules with
the most lines.

Run: .venv/bin/python benchmarks/layers.py [--largest 10] [--quick]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from common import parse_args  # noqa: E402

from test_layers import SRC, cycles, package_graph  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--largest", type=int, default=10, help="How many modules to list.")
    args = parse_args(ap, {"largest": 3})
    graph = package_graph(SRC.parent)
    print("Import graph between packages:")
    for source in sorted(graph):
        print(f"  {source} -> {', '.join(sorted(graph[source])) or '(nothing)'}")
    print(f"Cycles: {cycles(graph) or 'none'}")
    sizes = sorted(((len(p.read_text(encoding='utf-8').splitlines()), p.relative_to(SRC))
                    for p in SRC.rglob("*.py")), reverse=True)
    print(f"Largest modules ({len(sizes)} in all):")
    for lines, path in sizes[:args.largest]:
        print(f"  {lines:4d}  {path}")


if __name__ == "__main__":
    main()
