"""Seconds for a whole `arrange` of Task 1 on the embedded model, cold and warm.

Cold: a fresh `llm-grop arrange --task 1` process (imports, model load, all LLM
calls, sampling). Warm: the same arrangement again in one process whose model
is already loaded. Run: .venv/bin/python benchmarks/embedded_arrange.py
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time
from pathlib import Path

from llm_grop import arrange, make_llm


def main() -> None:
    exe = Path(sys.executable).with_name("llm-grop")
    cold = []
    for seed in range(3):
        t0 = time.perf_counter()
        subprocess.run([str(exe), "arrange", "--task", "1", "--seed", str(seed), "-q"], check=True)
        cold.append(time.perf_counter() - t0)
    llm = make_llm("embedded")
    arrange(task=1, llm=llm, seed=99)  # loads the model
    warm = []
    calls = []
    for seed in range(3):
        llm.calls.clear()
        t0 = time.perf_counter()
        arrange(task=1, llm=llm, seed=seed)
        warm.append(time.perf_counter() - t0)
        calls.append(len(llm.calls))
    print(f"embedded arrange, task 1: cold (new process) median {statistics.median(cold):.2f} s "
          f"over {len(cold)} runs: {', '.join(f'{t:.2f}' for t in cold)}")
    print(f"embedded arrange, task 1: warm (model loaded) median {statistics.median(warm):.2f} s "
          f"over the same {len(warm)} seeds: {', '.join(f'{t:.2f}' for t in warm)}; "
          f"LLM calls per run: {calls}")


if __name__ == "__main__":
    main()
