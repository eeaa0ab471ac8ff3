"""The paper's claims (§IV), one line each, checked against `llm-grop bench` results.

Reads ``summary.json`` from each results directory given and prints whether each claim
holds there:
* LLM-GROP has the highest mean rating;
* GROP is about as fast as LLM-GROP (mean execution times within 10 % of each other);
* TPRA and LATP are slower (both mean execution times above GROP's and LLM-GROP's);
and the targets set for settings that keep the LLM's geometry (issue 12), with a capable
LLM's relations (``--preferences``):
* LLM-GROP rates at least 4.5, above LATP and GROP;
* LLM-GROP executes faster than LATP, and within 3 % of GROP's execution time.
Run: .venv/bin/python benchmarks/paper_claims.py bench-replay [bench-preferences ...]
     .venv/bin/python benchmarks/paper_claims.py --quick   (a tiny bench of its own)
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from common import parse_args, results_dirs

#: "About as fast": mean execution times within this fraction of each other.
ABOUT_AS_FAST = 0.10
#: Issue 12's targets: LLM-GROP's mean rating, and its execution time's distance from GROP's.
RATING_TARGET = 4.5
NEAR_GROP = 0.03


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
    ours = rating["llm-grop"]
    out.append((f"target: LLM-GROP rates >= {RATING_TARGET}, above LATP and GROP",
                ours >= RATING_TARGET and ours > max(rating["latp"], rating["grop"]),
                f"llm-grop {ours:.2f}, latp {rating['latp']:.2f}, grop {rating['grop']:.2f}"))
    out.append(("target: LLM-GROP is faster than LATP", time_s["llm-grop"] < time_s["latp"],
                f"llm-grop {time_s['llm-grop']:.1f} s, latp {time_s['latp']:.1f} s"))
    off = (time_s["llm-grop"] - time_s["grop"]) / time_s["grop"]
    out.append((f"target: LLM-GROP within {100 * NEAR_GROP:g} % of GROP's time",
                abs(off) <= NEAR_GROP, f"{100 * off:+.1f}% of grop's {time_s['grop']:.1f} s"))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="*", type=Path)
    args = parse_args(ap)
    with results_dirs(ap, args) as dirs:
        for d in dirs:
            summary = json.loads((d / "summary.json").read_text())
            print(f"{d}:")
            print((d / "summary.md").read_text().rstrip())
            for claim, holds, evidence in claims(summary):
                print(f"  {claim}: {'holds' if holds else 'does not hold'} ({evidence})")


if __name__ == "__main__":
    main()
