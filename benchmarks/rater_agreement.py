"""How well the automatic rater agrees with a human on the hand-labelled arrangements.

Reads ``tests/evaluation/labelled/labels.yaml`` (one human's Table III labels, written
before the rater) and rates every file with :func:`llm_grop.evaluation.rate`. Prints
the exact agreement, the within-one agreement, a confusion table (human rows x
rater columns), and every disagreement with the rater's failed checks.

    python benchmarks/rater_agreement.py [--labelled DIR] [--quick]
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path

import yaml
from common import parse_args

from llm_grop.evaluation import rate

LABELLED = Path(__file__).resolve().parent.parent / "tests" / "evaluation" / "labelled"


def main(argv: list[str] | None = None) -> int:
    """Print the agreement figures; returns the process exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--labelled", type=Path, default=LABELLED,
                        help="folder with labels.yaml and the arrangement JSON files")
    args = parse_args(parser, argv=argv)  # --quick: the same, it takes seconds
    labels = yaml.safe_load((args.labelled / "labels.yaml").read_text(encoding="utf-8"))
    rows = []
    for name, label in labels["labels"].items():
        data = json.loads((args.labelled / name).read_text(encoding="utf-8"))
        rows.append((name, int(label["score"]), rate(data, where=name), label["reason"]))
    n = len(rows)
    exact = sum(h == r.score for _, h, r, _ in rows)
    within = sum(abs(h - r.score) <= 1 for _, h, r, _ in rows)
    bias = sum(r.score - h for _, h, r, _ in rows) / n
    print(f"{n} labelled arrangements")
    print(f"exact agreement:      {exact}/{n} = {exact / n:.0%}")
    print(f"within-one agreement: {within}/{n} = {within / n:.0%}")
    print(f"mean (rater - human): {bias:+.2f}")
    counts = Counter((h, r.score) for _, h, r, _ in rows)
    print("\nconfusion (rows: human, columns: rater)")
    print("       " + "".join(f"{s:>4}" for s in range(1, 6)))
    for h in range(1, 6):
        print(f"  {h}    " + "".join(f"{counts[(h, s)] or '.':>4}" for s in range(1, 6)))
    misses = [row for row in rows if row[1] != row[2].score]
    print(f"\ndisagreements ({len(misses)}):")
    for name, h, r, reason in misses:
        print(f"- {name}: human {h}, rater {r.score}")
        print(f"    human: {reason}")
        for c in r.failed:
            print(f"    rater: [{c.severity}] {c.name}: {c.detail}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
