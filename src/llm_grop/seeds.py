"""Every random stream of a run, derived from the run's one seed by a named stage.

A run has one seed (``--seed``). Each stage that draws random numbers asks this module
for a stream of its own, so stages never share numbers or consume each other's, and every
method run on the same seed sees the same room, chairs and object starts (the paper's
comparison is paired). The same seed, stage and path always give the same stream, in any
process.

====================== ====================================================== ==========
stage                  what it seeds                                          path
====================== ====================================================== ==========
``llm.relations``      the Template 1 call of each attempt                    attempt
``llm.followup``       the follow-up call for a left-out object               attempt, k
``llm.distance``       the Template 2 call of the k-th relation                k
``llm.edge``           the call asking the origin object's distance from the   0
                       diner's edge of the table
``llm.reading``        the call that reads a whole request the catalog         0
                       matcher cannot read alone
``llm.revision``       the feedback loop's k-th revision call, and its j-th    k (, j)
                       follow-up (``k, j``, from 1)
``sampler``            the LLM-guided Gaussian rejection sampler (M configs;   diner
                       per diner when the table seats several)
``random_arrangement`` the baselines' random collision-free arrangement
``chairs``             the chairs sampled near the target table
``scene``              where each requested object starts
``standing``           the baselines' uniform choice of standing positions
``ompl``               OMPL's RRTConnect for the plan's k-th navigation leg   k
``simulator``          the simulator's outcomes and noise
``ratings.order``      a human rater's order of a study's pictures            rater
``bootstrap``          the resamples of a paired comparison's confidence      pair
                       interval (a bench's summary, a human report)
``rescue``             the spots drawn for an object the feedback loop moves
``llm.generalise``     the call asking for general rules from the preferences  0
                       learned from examples
====================== ====================================================== ==========

OMPL takes its seed through a process-wide setting; the planner sets it, from the ``ompl``
stage, immediately before it builds each RRTConnect, whose state stays local to that call.

LLM calls keep the seeds llm-grop has always given them (stage ids 1-3), so recorded
answers (``--record``) still replay.
"""

from __future__ import annotations

import numpy as np

#: Stage name -> the number mixed into its seed. Numbers are never reused or changed.
STAGES: dict[str, int] = {
    "llm.relations": 1,
    "llm.followup": 2,
    "llm.distance": 3,
    "llm.edge": 4,
    # 5 was "llm.items", the per-chunk question of llm-grop 0.5-0.7; never reused.
    "sampler": 10,
    "random_arrangement": 11,
    "chairs": 12,
    "scene": 13,
    "standing": 14,
    "ompl": 15,
    "simulator": 16,
    "calibration": 17,
    "ratings.order": 18,
    "bootstrap": 19,
    "llm.reading": 20,
    "llm.revision": 21,
    "rescue": 22,
    "llm.generalise": 23,
}


def _sequence(seed: int, stage: str, path: tuple[int, ...]) -> np.random.SeedSequence:
    if stage not in STAGES:
        raise ValueError(f"unknown random stage {stage!r} (stages: {', '.join(STAGES)})")
    if seed < 0 or any(p < 0 for p in path):
        raise ValueError(f"seeds and paths must not be negative, got {seed}, {path}")
    return np.random.SeedSequence([seed, STAGES[stage], *path])


def stream(seed: int, stage: str, *path: int) -> np.random.Generator:
    """The random generator of ``stage`` (at ``path``) for the run seeded ``seed``."""
    return np.random.default_rng(_sequence(seed, stage, path))


def int_seed(seed: int, stage: str, *path: int) -> int:
    """A seed in ``[0, 2**31)`` for a library that takes an integer (an LLM call, OMPL)."""
    return int(_sequence(seed, stage, path).generate_state(1)[0] & 0x7FFFFFFF)
