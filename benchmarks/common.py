"""Shared set-up for the benchmark scripts: the recorded LLM and summary statistics."""

from __future__ import annotations

import math
import statistics
from pathlib import Path

from llm_grop import make_llm
from llm_grop.llm.base import BackendOptions, CallLog

#: Embedded-model answers for tasks 1-8 x seeds 0-19 and task 8 x seeds 20-49, written by
#: benchmarks/record_embedded.py.
RECORDING = Path(__file__).parent / "data" / "embedded_calls.jsonl"


def replay_llm() -> CallLog:
    """The embedded model's recorded answers, replayed (no model needed)."""
    if not RECORDING.exists():
        raise SystemExit(f"{RECORDING} is missing: run benchmarks/record_embedded.py first")
    return make_llm("replay", BackendOptions(replay_path=RECORDING))


def median_p95(values: list[float]) -> tuple[float, float]:
    """Median and 95th percentile (nearest rank) of ``values``."""
    ordered = sorted(values)
    return statistics.median(ordered), ordered[math.ceil(0.95 * len(ordered)) - 1]


def mean_se(values: list[float]) -> tuple[float, float]:
    """Mean and standard error of ``values``."""
    if len(values) < 2:
        return (values[0] if values else math.nan), math.nan
    return statistics.fmean(values), statistics.stdev(values) / math.sqrt(len(values))
