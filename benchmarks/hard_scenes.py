"""The hard-scene suite of the feedback loop (issue 41): each scene's first arrangement
fails (``data/hard_scenes.yaml``: a narrow table no placement of the usual relations fits,
an answer that contradicts itself every time it is asked, a spot the arm cannot reach that
the planner believes it can, and one it knows it cannot),
run without the loop
(``--revisions 0``, the paper's way) and with it (``--revisions 2``).

Each scene is run end to end (``llm_grop.run``: arrange, plan, execute in 2D, LLM-GROP, one
chair unless the scene's ``settings`` say otherwise) for ``--seeds`` seeds. The LLM is

* ``stand-in`` (default): a local OpenAI-compatible server on 127.0.0.1 that answers as the
  scene's ``stand_in`` says, as a capable model would: hand-written answers, not a model's
  output, labelled so;
* ``embedded``: the embedded model (SmolLM2-135M), run live; needs it installed.

Per scene and loop setting it prints the episodes with every object placed, the automatic
rating of the final table (1-5, mean over the episodes that executed), the episodes that
ended without a plan, the objects left unplaced and why, the relations dropped to restore
consistency, the rounds accepted and refused, the LLM calls per episode (median and
maximum) and the planning time (median; LLM calls excluded). With the stand-in, a third
line runs the scene with its revision answered first and no loop: what the loop aims at,
so what the scene's room and truth allow. Then, per scene, the LLM calls
and the planning time the loop added per episode (median and maximum over the seeds).
Run: .venv/bin/python benchmarks/hard_scenes.py [--seeds 10] [--llm stand-in|embedded]
     [--quick]
"""

from __future__ import annotations

import argparse
import math
import statistics
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from common import chat_server, parse_args

from llm_grop import BackendOptions, run
from llm_grop.contract.serialize import arrangement_doc
from llm_grop.errors import LLMGropError
from llm_grop.evaluation.rater import rate
from llm_grop.world.plan import RunResult

SCENES = Path(__file__).parent / "data" / "hard_scenes.yaml"
LOOP = {"without the loop (--revisions 0)": 0, "with the loop (--revisions 2)": 2}


@dataclass(frozen=True)
class Episode:
    """What one run gave (``error``: it ended before executing, with this message)."""

    placed_all: bool = False
    rating: float = math.nan
    dropped: int = 0
    accepted: int = 0
    refused: int = 0
    calls: int = 0
    planning_s: float = math.nan
    error: str | None = None
    execution_s: float = math.nan
    unplaced: tuple[str, ...] = ()


def stand_in(scene: Mapping[str, Any], first: str = "first") -> Any:
    """The reply function of the scene's stand-in for a capable model; it answers
    Template 1 with its ``first`` answer (``"revised"``: the revision, at once)."""
    said = scene["stand_in"]

    def reply(body: dict[str, Any]) -> str:
        prompt = body["messages"][-1]["content"]
        if "That answer cannot be used:" in prompt:
            return str(said["revised"])
        if "how many centimeters" in prompt.lower():
            return f"About {said['distance_cm']} centimeters."
        return str(said[first])

    return reply


def episode(scene: Mapping[str, Any], seed: int, revisions: int, llm: str,
            url: str | None) -> Episode:
    """One run of ``scene``."""
    opts = BackendOptions(base_url=url, api_key="stand-in", max_retries=0) if url else None
    try:
        r = run(scene["request"], table=scene["table"], seed=seed,
                method="llm-grop", llm="openai" if url else llm, llm_options=opts,
                revisions=revisions, **({"chairs": 1} | scene.get("settings", {})))
    except LLMGropError as exc:
        return Episode(error=str(exc).splitlines()[0])
    return outcome(r)


def outcome(r: RunResult) -> Episode:
    """What the figures need of the run ``r``."""
    planned = r.planned
    rating = rate(arrangement_doc(r.final, physical=True),
                  requested=[p.name for p in planned.placements]).score
    dropped = sum(w.startswith("dropped to restore consistency") for w in planned.warnings)
    outcomes = [v.outcome for v in planned.revisions]
    return Episode(r.success, rating, dropped, outcomes.count("accepted"),
                   outcomes.count("refused"), len(planned.llm.calls) if planned.llm else 0,
                   r.planning_time_s, execution_s=r.execution.execution_time_s,
                   unplaced=tuple(f"{n} {why}" for n, why in r.execution.unplaced_reasons))


def report(label: str, eps: list[Episode]) -> None:
    """One loop setting's line of figures."""
    ran = [e for e in eps if e.error is None]
    ratings = [e.rating for e in ran]
    calls = [e.calls for e in ran]
    print(f"  {label}: all placed {sum(e.placed_all for e in eps)}/{len(eps)}; rating "
          + (f"{statistics.fmean(ratings):.2f}" if ratings else "-")
          + f"; no plan {len(eps) - len(ran)}; relations dropped "
          f"{sum(e.dropped for e in ran)}; rounds accepted {sum(e.accepted for e in ran)}, "
          f"refused {sum(e.refused for e in ran)}; LLM calls per episode "
          + (f"median {statistics.median(calls):.0f}, max {max(calls)}" if calls else "-")
          + "; planning median "
          + (f"{1000 * statistics.median(e.planning_s for e in ran):.0f} ms" if ran else "-"))
    lost = Counter(u for e in ran for u in e.unplaced)
    if lost:
        print("    unplaced: " + ", ".join(f"{k} {v}" for k, v in lost.most_common()))
    errors = sorted({e.error for e in eps if e.error})
    for e in errors[:2]:
        print(f"    {e[:160]}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--llm", default="stand-in", choices=("stand-in", "embedded"))
    args = parse_args(ap, {"seeds": 1})
    scenes = yaml.safe_load(SCENES.read_text(encoding="utf-8"))["scenes"]
    state, httpd = chat_server()
    who = ("a local server answering as a capable model would (the scenes' stand_in: "
           "hand-written answers, not a model's output)" if args.llm == "stand-in"
           else "the embedded model (SmolLM2-135M), run live")
    print(f"hard-scene suite, {args.seeds} seeds per scene, LLM-GROP in 2D, 1 chair; LLM: {who}")
    try:
        for scene in scenes:
            state.reply = stand_in(scene)
            url = state.url if args.llm == "stand-in" else None
            print(f"{scene['name']} ({scene['kind']}), {scene['table']} m: "
                  f"{scene['request']!r}")
            print(f"  expected: without the loop, {scene['expected']['without']}; with it, "
                  f"{scene['expected']['with']}")
            runs = {}
            for label, revisions in LOOP.items():
                runs[revisions] = [episode(scene, seed, revisions, args.llm, url)
                                   for seed in range(args.seeds)]
                report(label, runs[revisions])
            if args.llm == "stand-in":
                # What the loop aims at: the revised relations, answered at once.
                state.reply = stand_in(scene, first="revised")
                report("the revision answered first, without the loop (its ceiling)",
                       [episode(scene, seed, 0, args.llm, url) for seed in range(args.seeds)])
            pairs = [(a, b) for a, b in zip(runs[0], runs[2], strict=True)
                     if a.error is None and b.error is None]
            added = [b.calls - a.calls for a, b in pairs]
            slower = [1000 * (b.planning_s - a.planning_s) for a, b in pairs]
            if pairs:
                print(f"  the loop added, over {len(pairs)} seeds both planned: LLM calls "
                      f"median {statistics.median(added):.0f}, max {max(added)}; planning "
                      f"time median {statistics.median(slower):.0f} ms, max "
                      f"{max(slower):.0f} ms")
    finally:
        httpd.shutdown()


if __name__ == "__main__":
    main()
