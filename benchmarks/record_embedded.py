"""Record the embedded model's answers for the paper's tasks, for offline replay.

Runs the arrangement (paper §III-A, §III-B) of each task and seed on the embedded
SmolLM2 model and appends every LLM call to a JSONL file that `--llm replay` reads.
Episodes (`llm-grop run`, the benchmarks) with the same task and seed then replay
these answers exactly, without the model. Tasks and seeds already in the file are
skipped, so an interrupted recording can be resumed.
Run: .venv/bin/python benchmarks/record_embedded.py --tasks 1-8 --seeds 0-19 \
        --out benchmarks/data/embedded_calls.jsonl
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from llm_grop import arrange, make_llm
from llm_grop.errors import LLMGropError


def _span(text: str) -> list[int]:
    """``"1-3,5"`` -> ``[1, 2, 3, 5]``."""
    out: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        out += range(int(lo), int(hi or lo) + 1)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", default="1-8")
    ap.add_argument("--seeds", default="0-19")
    ap.add_argument("--out", type=Path, default=Path("benchmarks/data/embedded_calls.jsonl"))
    args = ap.parse_args()
    done_file = args.out.with_suffix(".done")
    done = set(done_file.read_text().split()) if done_file.exists() else set()
    llm = make_llm("embedded", record=args.out)
    for task in _span(args.tasks):
        for seed in _span(args.seeds):
            key = f"{task}:{seed}"
            if key in done:
                continue
            llm.calls.clear()
            t0 = time.perf_counter()
            try:
                result = arrange(task=task, llm=llm, seed=seed)
                rels = len(result.arrangement.relations)
                status = f"{rels} relation(s)"
            except LLMGropError as exc:
                status = f"failed: {exc}"
            with done_file.open("a") as f:
                f.write(key + "\n")
            print(json.dumps({"task": task, "seed": seed, "calls": len(llm.calls),
                              "seconds": round(time.perf_counter() - t0, 1),
                              "status": status}), flush=True)


if __name__ == "__main__":
    main()
