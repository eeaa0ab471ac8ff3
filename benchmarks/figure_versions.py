"""Whether every figure in the README names the version and the script that measured it, and
whether that version is current.

A figure is a picture of ``docs/`` (embedded, ``![...](docs/...)``, or linked,
``[...](docs/....png)``), a paragraph that names the version it was measured with
(``version 0.17.0``, ``versions 0.9.0 and 0.11.0``), or a paragraph that names a script
under ``benchmarks/`` beside a quantity with its unit (``9.8 s``, ``35 ms``, ``97.3 %``),
which is taken for a measurement that must name its version. A paragraph may name older versions
beside the one it was measured with (what a figure was before a change); the newest
version it names is the measurement's. A picture's text is its own paragraph and the
paragraphs before and after it (its caption).

Each figure must name:

* a version whose major and minor numbers are the project's (``pyproject.toml``): the
  project's policy is that a release which changes what a figure measures bumps the minor
  version and re-measures the README's figures, while a patch release changes nothing a
  figure measures;
* what made it: a script that exists (``benchmarks/NAME.py``, a backticked ``NAME.py``
  under ``benchmarks/``, a test file ``tests/....py``) or an ``llm-grop`` command in
  backticks (a console sample printed by that command).

It prints each figure with its state; ``--check`` exits 1 when any figure is stale,
unversioned or names no script (``scripts/test.sh``, and so CI, runs it). It reads only
the README, so ``--quick`` does the same in well under a second.
Run: .venv/bin/python benchmarks/figure_versions.py [--readme README.md] [--check] [--quick]
"""

from __future__ import annotations

import argparse
import re
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

from common import parse_args

ROOT = Path(__file__).resolve().parent.parent
VERSION = re.compile(r"\bversions?\s+(\d+\.\d+\.\d+)(?:\s+and\s+(\d+\.\d+\.\d+))?")
SCRIPT = re.compile(r"\b((?:benchmarks|tests)/[A-Za-z_0-9/]+\.py)|`([a-z_0-9]+\.py)\b")
COMMAND = re.compile(r"`llm-grop\s+([a-z]+)")
PICTURE = re.compile(r"\]\((docs/[^)\s]+\.(?:png|jpg|gif|svg))\)")
BENCHMARK = re.compile(r"benchmarks/[a-z_0-9]+\.py|`[a-z_0-9]+\.py\b")
QUANTITY = re.compile(r"\d(?:\.\d+)? ?(?:(?:ms|s|MB|GB|minutes|cm|mm)\b|%)")


@dataclass(frozen=True)
class Figure:
    """One figure of the README: its first line, what it is, the versions its text names
    (oldest first) and what its text says made it (scripts and commands)."""

    line: int
    what: str
    versions: tuple[str, ...]
    makers: tuple[str, ...]


def _key(version: str) -> tuple[int, ...]:
    return tuple(int(part) for part in version.split("."))


def paragraphs(text: str) -> list[tuple[int, str]]:
    """The README's paragraphs (blank-line separated) with their first line's number; a
    fenced code block is part of the paragraph it starts in, blank lines included."""
    out, start, lines, fenced = [], 1, [], False
    for number, line in enumerate(text.splitlines(), 1):
        if line.startswith("```"):
            fenced = not fenced
        if line.strip() or fenced:
            if not lines:
                start = number
            lines.append(line)
        elif lines:
            out.append((start, "\n".join(lines)))
            lines = []
    if lines:
        out.append((start, "\n".join(lines)))
    return out


def _makers(text: str) -> tuple[str, ...]:
    scripts = {a or f"benchmarks/{b}" for a, b in SCRIPT.findall(text)}
    return tuple(sorted(scripts | {f"llm-grop {c}" for c in COMMAND.findall(text)}))


def inventory(text: str) -> list[Figure]:
    """Every figure of ``text`` (a README) in order."""
    found = []
    blocks = paragraphs(text)
    for k, (line, block) in enumerate(blocks):
        pictures = PICTURE.findall(block)
        near = block if not pictures else "\n".join(
            b for _, b in blocks[max(k - 1, 0):k + 2])
        versions = tuple(sorted({v for m in VERSION.finditer(near) for v in m.groups() if v},
                                key=_key))
        if pictures:
            what = "picture " + ", ".join(dict.fromkeys(pictures))
        elif VERSION.search(block) or (BENCHMARK.search(block) and QUANTITY.search(block)):
            what = "text: " + " ".join(block.split())[:60] + "…"
        else:
            continue
        found.append(Figure(line, what, versions, _makers(near)))
    return found


def problem(figure: Figure, current: str, root: Path = ROOT) -> str | None:
    """Why ``figure`` fails the check against version ``current``, or ``None``."""
    if not figure.versions:
        return "names no version"
    if _key(figure.versions[-1])[:2] != _key(current)[:2]:
        return f"measured with {figure.versions[-1]}, the project is {current}"
    if not figure.makers:
        return "names no script or command that made it"
    missing = [m for m in figure.makers if m.endswith(".py") and not (root / m).is_file()]
    if missing and len(missing) == len(figure.makers):
        return f"names {', '.join(missing)}, which does not exist"
    return None


def project_version(root: Path = ROOT) -> str:
    """The version in ``pyproject.toml`` (what the next release is called)."""
    with (root / "pyproject.toml").open("rb") as file:
        return tomllib.load(file)["project"]["version"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--readme", type=Path, default=ROOT / "README.md")
    parser.add_argument("--check", action="store_true",
                        help="exit 1 when any figure is stale, unversioned or names no script")
    args = parse_args(parser)
    if not args.readme.is_file():
        sys.exit(f"--readme {args.readme}: no such file")
    current = project_version()
    figures = inventory(args.readme.read_text(encoding="utf-8"))
    failing = 0
    print(f"README figures against llm-grop {current}:")
    for figure in figures:
        why = problem(figure, current)
        failing += why is not None
        print(f"  {'ok' if why is None else 'FAIL':4s} line {figure.line:5d}  "
              f"{', '.join(figure.versions) or '-':16s} {figure.what}"
              + (f"\n{'':18s}{why}" if why else ""))
    print(f"{len(figures)} figures, {failing} failing")
    if args.check and failing:
        print(f"{args.readme}: {failing} figures fail the check; re-measure them with the "
              "script they name, or remove them", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
