"""Fuzzing every text parser: many random, grammar-based and mutated inputs per parser.

The parsers and inputs are those of the fuzz tests (``tests/fuzz/fuzz_targets.py`` and
``tests/fuzz/fuzz_inputs.py``): the request parser, the LLM answer reader, the distance
parser, preferences and edge preferences (sentences), catalog and scene YAML (in memory;
bytes that are not UTF-8 go through a file), replay JSONL files, a replay record's round
trip through a file, and preferences files (a temporary file each case).
Every input must parse or raise one of the project's errors with a one-line message;
anything else is an *unexpected exception*. Inputs come from ``random.Random`` seeded by
``--seed`` and the parser's name, so a run repeats exactly (no Hypothesis).

Per parser it prints the cases run, each unexpected exception (type, where it was raised,
count, and the shortest input found for it, shrunk further by deleting pieces), and the
slowest case (seconds, wall clock, with a preview of its input). Then it times the answer
reader on two 1 MB answers (one line of repeated relations; varied lines).

Run: .venv/bin/python benchmarks/fuzz.py [--cases 50000] [--seed 0] [--parser NAME ...]
     [--max-seconds S] [--answer-bytes 1000000] [--quick]
"""

from __future__ import annotations

import argparse
import random
import sys
import time
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "fuzz"))

from common import parse_args  # noqa: E402
from fuzz_inputs import ITEMS, Input  # noqa: E402
from fuzz_targets import TARGETS, Target, check  # noqa: E402

from llm_grop.language.answer_reader import parse_relations  # noqa: E402
from llm_grop.world.catalog import Catalog  # noqa: E402

#: Characters of an input shown in the table.
PREVIEW = 160
#: Most attempts at shrinking one reproducer.
SHRINK_TRIES = 400


@dataclass
class Found:
    """One kind of unexpected exception: how often, and the shortest input raising it."""

    count: int
    example: Input
    message: str


@dataclass
class Report:
    """What fuzzing one parser found."""

    name: str
    cases: int = 0
    seconds: float = 0.0
    slowest_s: float = 0.0
    slowest: Input = ""
    found: dict[str, Found] = field(default_factory=dict)
    #: Warnings raised while parsing (not failures), by "category: message".
    warned: dict[str, Found] = field(default_factory=dict)


def _where(error: BaseException) -> str:
    """``Type at file:line`` of the innermost frame in the package (else the innermost)."""
    # A message over two lines is an AssertionError made by check(), caused by the error.
    frames = traceback.extract_tb((error.__cause__ or error).__traceback__)
    ours = [f for f in frames if "llm_grop" in f.filename] or frames
    at = f" at {Path(ours[-1].filename).name}:{ours[-1].lineno}" if ours else ""
    return f"{type(error).__name__}{at}"


def _shrink(target: Target, data: Input, key: str) -> Input:
    """``data`` with pieces deleted while ``target`` still fails the same way (``key``)."""
    tries = 0
    chunk = max(len(data) // 2, 1)
    while chunk >= 1 and tries < SHRINK_TRIES:
        i, shrunk = 0, False
        while i < len(data) and tries < SHRINK_TRIES:
            candidate = data[:i] + data[i + chunk:]
            tries += 1
            error = check(target, candidate)
            if error is not None and _where(error) == key:
                data, shrunk = candidate, True
            else:
                i += chunk
        if not shrunk:
            chunk //= 2
    return data


def _note(found: dict[str, Found], key: str, data: Input, message: str) -> None:
    """Counts one more ``key``, keeping the shortest input that gave it."""
    seen = found.get(key)
    if seen is None:
        found[key] = Found(1, data, message)
    else:
        seen.count += 1
        if len(data) < len(seen.example):
            seen.example, seen.message = data, message


def fuzz(target: Target, cases: int, seed: int, max_seconds: float) -> Report:
    """Runs ``target`` on ``cases`` inputs (or until ``max_seconds`` pass)."""
    rng = random.Random(f"{seed}:{target.name}")
    report = Report(target.name)
    start = time.perf_counter()
    while report.cases < cases and time.perf_counter() - start < max_seconds:
        data = target.sample(rng)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            t0 = time.perf_counter()
            error = check(target, data)
            elapsed = time.perf_counter() - t0
        for w in caught:
            _note(report.warned, f"{w.category.__name__}: {w.message}", data, str(w.message))
        report.cases += 1
        if elapsed > report.slowest_s:
            report.slowest_s, report.slowest = elapsed, data
        if error is None:
            continue
        _note(report.found, _where(error), data, str(error))
    report.seconds = time.perf_counter() - start
    for key, seen in report.found.items():
        seen.example = _shrink(target, seen.example, key)
    return report


def _preview(data: Input) -> str:
    text = repr(data)
    return text if len(text) <= PREVIEW else f"{text[:PREVIEW]}... ({len(data)} long)"


def print_report(report: Report) -> None:
    unexpected = sum(f.count for f in report.found.values())
    print(f"\n{report.name}: {report.cases} cases in {report.seconds:.1f} s, "
          f"{unexpected} unexpected exception(s)")
    for key, seen in sorted(report.found.items(), key=lambda kv: -kv[1].count):
        message = seen.message.splitlines()[0][:120] if seen.message else ""
        print(f"  {seen.count:6d}  {key}: {message}")
        print(f"          reproducer: {_preview(seen.example)}")
    for key, seen in report.warned.items():
        print(f"  {seen.count:6d}  warning {key[:120]}")
        print(f"          e.g.: {_preview(seen.example)}")
    print(f"  slowest case: {report.slowest_s:.4f} s on {_preview(report.slowest)}")


def _summary(reports: list[Report]) -> None:
    print("\n| parser | cases | unexpected | kinds | slowest case (s) |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for r in reports:
        print(f"| {r.name} | {r.cases} | {sum(f.count for f in r.found.values())} | "
              f"{len(r.found)} | {r.slowest_s:.4f} |")


def one_megabyte_answers(size_bytes: int = 1_000_000) -> None:
    """Times the answer reader on 1 MB answers (``size_bytes``): one line of repeated
    relations, and varied lines mixing relations, prose and numbering."""
    catalog = Catalog.load(use_env=False)
    unit = "Place the fork to the left of the plate and the knife to the right. "
    one_line = (unit * (size_bytes // len(unit) + 1))[:size_bytes]
    rng = random.Random(0)
    names = sorted({it.kind for it in ITEMS})
    relations = ["to the left of", "to the right of", "above", "below", "on top of",
                 "behind", "in front of", "above and to the right of", "slightly left of"]
    lines: list[str] = []
    size = 0
    while size < size_bytes:
        k = rng.random()
        if k < 0.5:
            line = (f"{rng.randint(1, 99)}. Place the {rng.choice(names)} "
                    f"{rng.choice(relations)} the {rng.choice(names)}.")
        elif k < 0.7:
            line = " ".join(f"word{rng.randint(0, 10**6)}" for _ in range(12)) + "."
        else:
            line = (f"The {rng.choice(names)} {rng.choice(relations)} and the "
                    f"{rng.choice(names)} {rng.choice(relations)} the {rng.choice(names)}.")
        lines.append(line)
        size += len(line) + 1
    varied = "\n".join(lines)[:size_bytes]
    print()
    mb = f"{size_bytes / 1e6:g} MB answer"
    for label, text in ((f"{mb}, one line", one_line), (f"{mb}, varied lines", varied)):
        start = time.perf_counter()
        parsed = parse_relations(text, ITEMS, catalog)
        elapsed = time.perf_counter() - start
        print(f"{label}: {elapsed:.2f} s ({len(parsed.relations)} relations, "
              f"{len(parsed.ignored)} ignored entries, longest "
              f"{max(map(len, parsed.ignored), default=0)} characters)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=50_000, help="Inputs per parser.")
    ap.add_argument("--seed", type=int, default=0, help="Seed of the random inputs.")
    ap.add_argument("--parser", choices=sorted(TARGETS), action="append",
                    help="A parser to fuzz (repeatable); all when not given.")
    ap.add_argument("--max-seconds", type=float, default=600.0,
                    help="Most seconds per parser (fewer cases are run when it is reached).")
    ap.add_argument("--answer-bytes", type=int, default=1_000_000,
                    help="Size of the long answers the reader is timed on.")
    args = parse_args(ap, {"cases": 100, "answer_bytes": 20_000})
    reports = []
    for name in args.parser or list(TARGETS):
        report = fuzz(TARGETS[name], args.cases, args.seed, args.max_seconds)
        print_report(report)
        reports.append(report)
    _summary(reports)
    if args.parser is None or "answer" in args.parser:
        one_megabyte_answers(args.answer_bytes)


if __name__ == "__main__":
    main()
