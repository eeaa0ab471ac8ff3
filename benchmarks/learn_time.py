"""Issue 42's figure: the time to learn a style from 3 example settings.

Three settings of a left-handed diner (a dinner plate, fork, knife and mug, set by the
pipeline from the style's preferences with seeds 1-3, no LLM call) are written as
arrangement JSON to a scratch directory; ``learn()`` then reads and learns from the three
files ``--repeats`` times (files read each time, the catalog loaded once), and
``llm-grop learn --exact`` (no LLM asked) runs as a user runs it, Python's start
included, ``--runs`` times.
Prints the median and 95th percentile of each, and what was learned.
Run: .venv/bin/python benchmarks/learn_time.py [--repeats 200] [--runs 5] [--quick]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import median_p95, parse_args, write_settings

from llm_grop import learn
from llm_grop.world.catalog import Catalog

SETTING = "a dinner plate, a dinner fork, a dinner knife and a mug"
LEFT_HANDED = ("the dinner plate 4 cm from the diner's edge of the table",
               "the dinner fork 3 cm to the right of the dinner plate",
               "the dinner knife 2 cm to the left of the dinner plate",
               "the mug 3 cm above and to the left of the dinner plate")


def examples(where: Path, catalog: Catalog) -> list[Path]:
    """Three settings in the left-handed style, as arrangement JSON files in ``where``."""
    return write_settings(where, SETTING, LEFT_HANDED, (1, 2, 3), catalog)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=200)
    ap.add_argument("--runs", type=int, default=5)
    args = parse_args(ap, {"repeats": 3, "runs": 1})
    catalog = Catalog.load(use_env=False)
    with tempfile.TemporaryDirectory() as scratch:
        files = examples(Path(scratch), catalog)
        seconds = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            learned = learn(files, catalog=catalog)
            seconds.append(time.perf_counter() - t0)
        med, p95 = median_p95(seconds)
        print(f"learn() from 3 example settings ({len(learned.sentences)} sentences learned), "
              f"{args.repeats} repeats: median {1000 * med:.1f} ms, p95 {1000 * p95:.1f} ms")
        command = []
        for k in range(args.runs):
            out = Path(scratch) / f"prefs{k}.yaml"
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "llm_grop", "learn", *map(str, files),
                            "--out", str(out), "--exact", "-q"], check=True)
            command.append(time.perf_counter() - t0)
        med, p95 = median_p95(command)
        print(f"llm-grop learn --exact with 3 examples, Python's start included, {args.runs} runs: "
              f"median {med:.2f} s, p95 {p95:.2f} s")
        for s in learned.sentences:
            print(f"  {s.sentence}")


if __name__ == "__main__":
    main()
