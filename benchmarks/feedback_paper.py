"""The feedback loop on the paper's experiment (issue 41): LLM-GROP on the 8 tasks x 20
seeds without the loop (``--revisions 0``, the paper's blind re-prompt) and with it
(``--revisions 2``), per task: the automatic rating, the execution time and the episodes
with every object placed; and the LLM calls and planning time the loop added per episode.

The LLM (``--llm``) is

* ``embedded`` (default): the embedded model (SmolLM2-135M): its recorded answers to the
  paper's prompts (``data/embedded_calls.jsonl``, what every paper figure replays), and the
  model itself, run live, for the prompts the recording lacks (the revision prompts, their
  follow-ups and the distances of the relations a revision adds). Without the loop every
  answer is recorded. ``--quick``, and a machine without the model (``--no-live``), refuse
  every revision round (a recording lacks them), so both sides are the same runs;
* ``stand-in``: a local OpenAI-compatible server on 127.0.0.1 answering as a capable model
  would: Template 1 with the relations of ``data/preferences.yaml`` (the usual way, written
  by hand) between the task's objects, 3 cm to every distance, and the same answer to a
  revision prompt. Hand-written answers, not a model's output.

2D, one chair, the bench's scene.
Run: .venv/bin/python benchmarks/feedback_paper.py [--seeds 20] [--tasks 1-8]
     [--llm embedded|stand-in] [--no-live] [--quick]
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from common import RECORDING, chat_server, parse_args, span
from hard_scenes import Episode, outcome, stand_in
from record_embedded import FillIn

from llm_grop import BackendOptions, make_llm, run
from llm_grop.api import resolve_items
from llm_grop.arrangement.preferences import load_preference_file
from llm_grop.errors import LLMGropError
from llm_grop.language.answer_reader import parse_relations
from llm_grop.llm.base import LLM
from llm_grop.llm.registry import create_llm
from llm_grop.world.catalog import Catalog

DATA = Path(__file__).parent / "data"


#: A fresh backend for one run, and how many of its calls a live model answered.
Fresh = Callable[[], tuple[LLM, Callable[[], int]]]


def recorded(live: LLM | None) -> Fresh:
    """The embedded model's recording, and ``live`` for what it lacks."""
    def fresh() -> tuple[LLM, Callable[[], int]]:
        backend = FillIn(RECORDING, live, write=False)
        return backend, lambda: backend.filled
    return fresh


def stand_in_answer(task: int) -> str:
    """The stand-in's Template 1 answer for ``task``: every relation of the hand-written
    preferences between its objects, one "Place ..." line each."""
    catalog = Catalog.load(use_env=False)
    _, items = resolve_items(None, task, catalog)
    pool = load_preference_file(DATA / "preferences.yaml")
    lines = [r.sentence() for sentence in pool
             for r in parse_relations(sentence, items, catalog).relations]
    return "\n".join(dict.fromkeys(lines))


def said(answer: str) -> dict[str, Any]:
    """A scene whose ``stand_in`` (as a hard scene's) says ``answer`` to Template 1 and
    again to a revision prompt, and 3 cm to every distance."""
    return {"stand_in": {"first": answer, "revised": answer, "distance_cm": 3}}


def task_runs(task: int, seeds: int, revisions: int, fresh: Fresh
              ) -> tuple[list[Episode], int]:
    """LLM-GROP on ``task`` for each seed; the episodes and the live LLM calls."""
    out, live_calls = [], 0
    for seed in range(seeds):
        backend, filled = fresh()
        try:
            r = run(task=task, seed=seed, chairs=1, method="llm-grop",
                    llm=make_llm(backend), revisions=revisions)
            out.append(outcome(r))
        except LLMGropError as exc:
            out.append(Episode(error=str(exc).splitlines()[0]))
        live_calls += filled()
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
    ap.add_argument("--llm", default="embedded", choices=("embedded", "stand-in"))
    ap.add_argument("--no-live", action="store_true",
                    help="no embedded model: revision rounds are refused")
    args = parse_args(ap, {"seeds": 1, "tasks": "8", "no_live": True})
    try:
        tasks = span(args.tasks)
    except ValueError:
        ap.error(f"--tasks: expected tasks such as 1-8 or 1,3,5, got {args.tasks!r}")
    if args.llm == "stand-in":
        state, _ = chat_server()
        options = BackendOptions(base_url=state.url, api_key="stand-in", max_retries=0)
        fresh: Fresh = lambda: (create_llm("openai", options), lambda: 0)  # noqa: E731
        print(f"LLM-GROP, tasks {args.tasks} x {args.seeds} seeds, 2D, 1 chair; LLM: a local "
              "server answering as a capable model would (the relations of "
              "data/preferences.yaml: hand-written answers, not a model's output)")
    else:
        live = None if args.no_live else create_llm("embedded", BackendOptions())
        fresh = recorded(live)
        print(f"LLM-GROP, tasks {args.tasks} x {args.seeds} seeds, 2D, 1 chair; LLM: the "
              "embedded model (SmolLM2-135M), its recorded answers"
              + (", and run live for the prompts the recording lacks" if live else
                 "; no live model: every revision round is refused"))
    added_calls: list[int] = []
    added_ms: list[float] = []
    # A first run warms the process up (imports, caches), so that no side's planning
    # time carries it.
    if args.llm == "stand-in":
        state.reply = stand_in(said(stand_in_answer(tasks[0])))
    task_runs(tasks[0], 1, 0, fresh if args.llm == "stand-in" else recorded(None))
    t0 = time.perf_counter()
    worse = []
    for task in tasks:
        if args.llm == "stand-in":
            state.reply = stand_in(said(stand_in_answer(task)))
        off, _ = task_runs(task, args.seeds, 0, fresh)
        on, live_calls = task_runs(task, args.seeds, 2, fresh)
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
