"""Seconds for a whole `arrange` of Task 1 on the embedded model, cold and warm.

Cold: a fresh `llm-grop arrange --task 1` process (imports, model load, all LLM
calls, sampling). Warm: the same arrangement again in one process whose model
is already loaded. ``--llm replay`` times the same with the model's recorded answers
replayed (``--replay FILE``, by default ``benchmarks/data/embedded_calls.jsonl``): what
``--quick`` does, once each (the model takes minutes on a busy 2-core machine).
Run: .venv/bin/python benchmarks/embedded_arrange.py [--runs 3] [--llm embedded|replay]
     [--replay FILE] [--quick]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

from common import RECORDING, parse_args

from llm_grop import BackendOptions, arrange, make_llm


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3, help="seeds timed, cold and warm")
    ap.add_argument("--llm", default="embedded", choices=("embedded", "replay"))
    ap.add_argument("--replay", type=Path, default=RECORDING, help="the recording to replay")
    args = parse_args(ap, {"runs": 1, "llm": "replay"})
    exe = Path(sys.executable).with_name("llm-grop")
    backend = ["--llm", "replay", "--replay", str(args.replay)] if args.llm == "replay" else []
    cold = []
    for seed in range(args.runs):
        t0 = time.perf_counter()
        subprocess.run([str(exe), "arrange", "--task", "1", "--seed", str(seed), "-q",
                        *backend], check=True)
        cold.append(time.perf_counter() - t0)
    llm = make_llm(args.llm, BackendOptions(replay_path=args.replay))
    # Loads the model (a seed the recording holds, for the replay).
    arrange(task=1, llm=llm, seed=19 if args.llm == "replay" else 99)
    warm = []
    calls = []
    for seed in range(args.runs):
        llm.calls.clear()
        t0 = time.perf_counter()
        arrange(task=1, llm=llm, seed=seed)
        warm.append(time.perf_counter() - t0)
        calls.append(len(llm.calls))
    print(f"{args.llm} arrange, task 1: cold (new process) median "
          f"{statistics.median(cold):.2f} s over {len(cold)} runs: "
          f"{', '.join(f'{t:.2f}' for t in cold)}")
    print(f"{args.llm} arrange, task 1: warm (model loaded) median "
          f"{statistics.median(warm):.2f} s over the same {len(warm)} seeds: "
          f"{', '.join(f'{t:.2f}' for t in warm)}; LLM calls per run: {calls}")


if __name__ == "__main__":
    main()
