"""Which of the README's figures are stale: an inventory for issue 38's re-measurement.

A figure here is a picture (``![...](docs/...)``) or a paragraph that names the version it
was measured with (``version 0.11.0``). For each, it prints the README line, the versions
the figure's paragraph names, the scripts under ``benchmarks/`` it names, and whether it
is older than the installed package. A picture whose paragraph or caption (the paragraph
before and after it) names no version is listed as unversioned. It reads the README only,
so ``--quick`` prints the same in well under a second.
Run: .venv/bin/python benchmarks/figure_versions.py [--readme README.md] [--quick]
"""

from __future__ import annotations

import argparse
import re
from importlib import metadata
from pathlib import Path

from common import parse_args

VERSION = re.compile(r"\bversions? (\d+\.\d+\.\d+)(?: and (\d+\.\d+\.\d+))?")
SCRIPT = re.compile(r"benchmarks/([a-z_0-9]+\.py)|`([a-z_0-9]+\.py)`")
PICTURE = re.compile(r"^!\[[^\]]*\]\((docs/[^)]+)\)")


def _key(version: str) -> tuple[int, ...]:
    return tuple(int(part) for part in version.split("."))


def paragraphs(text: str) -> list[tuple[int, str]]:
    """The README's paragraphs (blank-line separated) with their first line's number."""
    out, start, lines = [], 1, []
    for number, line in enumerate(text.splitlines(), 1):
        if line.strip():
            if not lines:
                start = number
            lines.append(line)
        elif lines:
            out.append((start, "\n".join(lines)))
            lines = []
    if lines:
        out.append((start, "\n".join(lines)))
    return out


def inventory(text: str) -> list[tuple[int, str, list[str], list[str]]]:
    """Each figure: its line, what it is, the versions and the scripts its text names."""
    found = []
    blocks = paragraphs(text)
    for k, (line, block) in enumerate(blocks):
        picture = PICTURE.match(block)
        near = block if not picture else "\n".join(
            b for _, b in blocks[max(k - 1, 0):k + 2])
        versions = sorted({v for m in VERSION.finditer(near) for v in m.groups() if v},
                          key=_key)
        scripts = sorted({a or b for a, b in SCRIPT.findall(near)})
        if picture:
            found.append((line, f"picture {picture[1]}", versions, scripts))
        elif VERSION.search(block):
            first = " ".join(block.split())[:60]
            found.append((line, f"text: {first}…", versions, scripts))
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--readme", type=Path,
                        default=Path(__file__).resolve().parent.parent / "README.md")
    args = parse_args(parser)
    current = metadata.version("llm-grop")
    figures = inventory(args.readme.read_text(encoding="utf-8"))
    stale = 0
    print(f"README figures against llm-grop {current}:")
    for line, what, versions, scripts in figures:
        if not versions:
            state = "UNVERSIONED"
        elif _key(versions[-1]) < _key(current):
            state = "stale"
        else:
            state = "current"
        stale += state != "current"
        print(f"  {state:11s} line {line:5d}  {', '.join(versions) or '-':16s} "
              f"{', '.join(scripts) or '-':30s} {what}")
    print(f"{len(figures)} figures, {stale} stale or unversioned")


if __name__ == "__main__":
    main()
