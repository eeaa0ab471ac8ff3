"""The paper's claims (§IV), one line each, checked against `llm-grop bench` results.

Reads ``summary.json`` from each results directory given and prints whether each claim
holds there:
* LLM-GROP has the highest mean rating;
* GROP is about as fast as LLM-GROP (mean execution times within 10 % of each other);
* TPRA and LATP are slower (both mean execution times above GROP's and LLM-GROP's).
Run: .venv/bin/python benchmarks/paper_claims.py bench-replay [bench-preferences ...]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

#: "About as fast": mean execution times within this fraction of each other.
ABOUT_AS_FAST = 0.10


def claims(summary: dict) -> list[tuple[str, bool, str]]:
    """``(claim, holds, evidence)`` for the paper's three claims."""
    by = {m["method"]: m for m in summary["methods"]}
    rating = {k: v["rating"]["mean"] for k, v in by.items()}
    time_s = {k: v["execution_time_s"]["mean"] for k, v in by.items()}
    best = max(rating, key=lambda k: rating[k])
    out = [("LLM-GROP has the highest rating", best == "llm-grop",
            ", ".join(f"{k} {v:.2f}" for k, v in rating.items()))]
    gap = abs(time_s["grop"] - time_s["llm-grop"]) / time_s["llm-grop"]
    out.append(("GROP is about as fast as LLM-GROP", gap <= ABOUT_AS_FAST,
                f"grop {time_s['grop']:.1f} s, llm-grop {time_s['llm-grop']:.1f} s "
                f"({100 * gap:.1f}% apart)"))
    fast = max(time_s["grop"], time_s["llm-grop"])
    out.append(("TPRA and LATP are slower", min(time_s["tpra"], time_s["latp"]) > fast,
                f"tpra {time_s['tpra']:.1f} s, latp {time_s['latp']:.1f} s vs "
                f"at most {fast:.1f} s"))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="+", type=Path)
    args = ap.parse_args()
    for d in args.dirs:
        summary = json.loads((d / "summary.json").read_text())
        print(f"{d}:")
        print((d / "summary.md").read_text().rstrip())
        for claim, holds, evidence in claims(summary):
            print(f"  {claim}: {'holds' if holds else 'does not hold'} ({evidence})")


if __name__ == "__main__":
    main()
