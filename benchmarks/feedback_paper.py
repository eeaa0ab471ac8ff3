"""The feedback loop on the paper's experiment (issue 41): LLM-GROP on the 8 tasks x 20
seeds without the loop (``--revisions 0``, the paper's blind re-prompt) and with it
(``--revisions 2``), per task: the automatic rating, the execution time and the episodes
with every object placed; and the LLM calls and planning time the loop added per episode.

The LLM is the embedded model (SmolLM2-135M): its recorded answers to the paper's prompts
(``data/embedded_calls.jsonl``, what every paper figure replays), and the model itself, run
live, for the prompts the recording lacks (the revision prompts, and the distances of the
relations a revision adds). Without the loop every answer is recorded. ``--quick``, and a
machine without the model (``--no-live``), refuse every revision round (a recording lacks
them), so both sides are the same runs. 2D, one chair, the bench's scene.
Run: .venv/bin/python benchmarks/feedback_paper.py [--seeds 20] [--tasks 1-8] [--no-live]
     [--quick]
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Sequence

from common import RECORDING, parse_args
from hard_scenes import Episode, outcome
from record_embedded import FillIn

from llm_grop import BackendOptions, make_llm, run
from llm_grop.errors import LLMGropError
from llm_grop.llm.base import LLM
from llm_grop.llm.registry import create_llm


def task_runs(task: int, seeds: int, revisions: int, live: LLM | None
              ) -> tuple[list[Episode], int]:
    """LLM-GROP on ``task`` for each seed; the episodes and the live LLM calls."""
    out, live_calls = [], 0
    for seed in range(seeds):
        backend = FillIn(RECORDING, live, write=False)
        try:
            r = run(task=task, seed=seed, chairs=1, method="llm-grop",
                    llm=make_llm(backend), revisions=revisions)
            out.append(outcome(r))
        except LLMGropError as exc:
            out.append(Episode(error=str(exc).splitlines()[0]))
        live_calls += backend.filled
    return out, live_calls


def summary(eps: Sequence[Episode]) -> str:
    """Rating (mean), execution time (median, simulated) and all placed of ``eps``."""
    ran = [e for e in eps if e.error is None]
    if not ran:
        return "no episode planned"
    return (f"rating {statistics.fmean(e.rating for e in ran):.2f}, execution "
            f"{statistics.median(e.execution_s for e in ran):.1f} s, all placed "
            f"{sum(e.placed_all for e in ran)}/{len(eps)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--tasks", default="1-8")
    ap.add_argument("--no-live", action="store_true",
                    help="no embedded model: revision rounds are refused")
    args = parse_args(ap, {"seeds": 1, "tasks": "8", "no_live": True})
    first, _, last = args.tasks.partition("-")
    tasks = range(int(first), int(last or first) + 1)
    live = None if args.no_live else create_llm("embedded", BackendOptions())
    print(f"LLM-GROP, tasks {args.tasks} x {args.seeds} seeds, 2D, 1 chair; LLM: the embedded "
          "model (SmolLM2-135M), its recorded answers"
          + (", and run live for the prompts the recording lacks" if live else
             "; no live model: every revision round is refused"))
    added_calls: list[int] = []
    added_ms: list[float] = []
    # A first run warms the process up (imports, caches), so that no side's planning
    # time carries it.
    task_runs(tasks[0], 1, 0, None)
    t0 = time.perf_counter()
    worse = []
    for task in tasks:
        off, _ = task_runs(task, args.seeds, 0, live)
        on, live_calls = task_runs(task, args.seeds, 2, live)
        print(f"task {task}: without the loop {summary(off)}; with it {summary(on)}; "
              f"rounds accepted {sum(e.accepted for e in on)}, refused "
              f"{sum(e.refused for e in on)}; live LLM calls {live_calls}", flush=True)
        for a, b in zip(off, on, strict=True):
            if a.error is None and b.error is None:
                added_calls.append(b.calls - a.calls)
                added_ms.append(1000 * (b.planning_s - a.planning_s))
        ran_off = [e for e in off if e.error is None]
        ran_on = [e for e in on if e.error is None]
        if ran_off and ran_on and (
                statistics.fmean(e.rating for e in ran_on)
                < statistics.fmean(e.rating for e in ran_off) - 1e-9
                or sum(e.placed_all for e in on) < sum(e.placed_all for e in off)):
            worse.append(task)
    if added_calls:
        print(f"the loop added per episode: LLM calls median "
              f"{statistics.median(added_calls):.0f}, max {max(added_calls)}; planning time "
              f"median {statistics.median(added_ms):.0f} ms, max {max(added_ms):.0f} ms")
    print(f"tasks worse with the loop (rating or all placed): "
          f"{', '.join(map(str, worse)) or 'none'} ({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
