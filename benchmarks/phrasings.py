"""Requests in people's own words: how the corpus of phrasings is read, and what it costs.

The corpus is ``tests/language/phrasings.yaml`` (requests as people write them, each with
the reading a person means; a reading is the same when its diners, objects, counts, where
each object came from, and relations with their distances agree). It is read:

- (a) by the fast path, the catalog matcher alone: read exactly, left to the LLM, or read
  wrongly;
- (b) by the LLM path through a local OpenAI-compatible server that answers each phrasing
  with its expected reading (a hand-written answer, not a model's output): whether a good
  answer is carried through unchanged;
- (c) by the embedded SmolLM2-135M model: the LLM path on every phrasing (the model's own
  reading), and the system as a user runs it (the fast path, the model for the rest).
  ``--llm replay --replay FILE`` replays a recording of (c) instead of running the model;
  ``--record FILE`` writes one.

It also lists the requests refused before any LLM call while an LLM was configured (every
phrasing and refusal of the corpus; the target is only those with no dining word), and the
median and p95 added latency of the reading call.

Run: .venv/bin/python benchmarks/phrasings.py --llm embedded \
        --record benchmarks/data/phrasings_embedded.jsonl
     .venv/bin/python benchmarks/phrasings.py --llm replay \
        --replay benchmarks/data/phrasings_embedded.jsonl
     .venv/bin/python benchmarks/phrasings.py --quick   (the replay; (b) and (c) on a few phrasings)
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The embedded model's readings of the corpus, recorded (what ``--quick`` replays).
RECORDED = ROOT / "benchmarks" / "data" / "phrasings_embedded.jsonl"
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "tests" / "language"))

from common import chat_server, median_p95, parse_args  # noqa: E402
from corpus import Case, as_answer, load_cases, load_refusals, same  # noqa: E402

from llm_grop import BackendOptions, make_llm  # noqa: E402
from llm_grop.errors import LLMGropError  # noqa: E402
from llm_grop.language.llm_reading import answer_of  # noqa: E402
from llm_grop.language.request import read_request  # noqa: E402
from llm_grop.language.understanding import (  # noqa: E402
    may_name_tableware,
    read_with_llm,
    understand,
)
from llm_grop.llm.base import CallLog  # noqa: E402
from llm_grop.llm.openai_backend import OpenAILLM  # noqa: E402
from llm_grop.world.catalog import Catalog  # noqa: E402


def fast_path(cases: list[Case], catalog: Catalog) -> Counter[str]:
    """(a): per phrasing "exact", "left to the LLM" or "wrong"."""
    out = Counter[str]()
    for case in cases:
        try:
            fast = read_request(case.text, catalog)
        except LLMGropError:
            out["refused"] += 1
            continue
        if fast.reading is None:
            out["left to the LLM"] += 1
        elif same(fast.reading, case.expected):
            out["exact"] += 1
        else:
            out["wrong"] += 1
            print(f"  (a) wrong: {case.text!r}")
    return out


def answered(cases: list[Case], catalog: Catalog) -> Counter[str]:
    """(b): the LLM path on every phrasing, the server answering its expected reading."""
    state, httpd = chat_server()
    log = CallLog(OpenAILLM(BackendOptions(base_url=state.url, max_retries=0)))
    out = Counter[str]()
    for case in cases:
        state.reply = lambda body, case=case: answer_of(as_answer(case.expected))
        got = read_with_llm(read_request(case.text, catalog), catalog, log).reading
        out["exact" if same(got, case.expected) else "not exact"] += 1
    httpd.shutdown()
    return out


def model(cases: list[Case], catalog: Catalog, llm: CallLog, verbose: bool
          ) -> tuple[Counter[str], Counter[str], list[float], list[float]]:
    """(c): the model's reading of every phrasing, and the system's (fast path first);
    with the calls' recorded latencies and this process's wall time per call, seconds."""
    alone, system = Counter[str](), Counter[str]()
    latency, wall = [], []
    for k, case in enumerate(cases, 1):
        fast = read_request(case.text, catalog)
        t0 = time.perf_counter()
        try:
            got = read_with_llm(fast, catalog, llm).reading
            ok = same(got, case.expected)
            shown = f"{got.diners} x " + ", ".join(f"{o.count} {o.name}" for o in got.objects)
        except LLMGropError as exc:
            ok, shown = False, f"error: {exc}"
        wall.append(time.perf_counter() - t0)
        latency.append(llm.calls[-1].latency_s)
        alone["exact" if ok else "not exact"] += 1
        if fast.reading is not None:
            system["exact (fast path)" if same(fast.reading, case.expected) else "wrong"] += 1
        else:
            system["exact (model)" if ok else "not exact (model)"] += 1
        if verbose:
            print(f"{k:3d}. {'ok ' if ok else '-- '}{case.text!r}: {shown}")
    return alone, system, latency, wall


def refused_before_asking(catalog: Catalog) -> list[tuple[str, str]]:
    """Every corpus request refused before any LLM call while an LLM was configured, with
    its error (the LLM here is a recording of no call: a call would fail loudly)."""
    texts = [c.text for c in load_cases()] + [t for t, _ in load_refusals()]
    out = []
    for text in texts:
        llm = make_llm("replay", BackendOptions(
            replay_path=ROOT / "tests" / "arrangement" / "no_calls.jsonl"))
        try:
            understand(text, catalog, llm)
        except LLMGropError as exc:
            if not llm.calls and "no recorded response" not in str(exc):
                out.append((text, str(exc)))
    return out


def _table(title: str, counts: Counter[str], n: int) -> None:
    print(f"{title} ({n} phrasings): " + ", ".join(
        f"{label} {k} ({100 * k / n:.1f} %)" for label, k in counts.most_common()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--llm", default="embedded", choices=("embedded", "replay"))
    parser.add_argument("--replay", type=Path)
    parser.add_argument("--record", type=Path)
    parser.add_argument("--limit", type=int, help="Read only the first N phrasings in (c).")
    parser.add_argument("--served", type=int, help="Read only the first N phrasings in (b).")
    parser.add_argument("-v", "--verbose", action="store_true")
    args = parse_args(parser, {"llm": "replay", "replay": RECORDED, "limit": 5, "served": 10})
    if args.record is not None and args.record.exists():
        args.record.unlink()  # a fresh recording of this run's calls
    catalog = Catalog.load(use_env=False)
    cases = load_cases()
    n = len(cases)
    print(f"corpus: {n} phrasings, {len(load_refusals())} refusals")
    _table("(a) fast path", fast_path(cases, catalog), n)
    served = cases[:args.served] if args.served else cases
    _table("(b) LLM path, a server answering each expected reading", answered(served, catalog),
           len(served))
    llm = make_llm(args.llm, BackendOptions(replay_path=args.replay), record=args.record)
    read = cases[:args.limit] if args.limit else cases
    alone, system, latency, wall = model(read, catalog, llm, args.verbose)
    label = llm.model if args.llm == "embedded" else f"replay of {args.replay}"
    _table(f"(c) {label}, reading every phrasing", alone, len(read))
    _table(f"(c) llm-grop with {label} for what the fast path leaves", system, len(read))
    med, p95 = median_p95(latency)
    print(f"reading call, {args.llm}: recorded latency median {med:.2f} s, p95 {p95:.2f} s")
    med, p95 = median_p95(wall)
    print(f"reading call, {args.llm}: this process's wall time per call median "
          f"{1000 * med:.1f} ms, p95 {1000 * p95:.1f} ms")
    refused = refused_before_asking(catalog)
    gate = [(t, e) for t, e in refused if not may_name_tableware(t, catalog)]
    other = [(t, e) for t, e in refused if may_name_tableware(t, catalog)]
    print(f"refused before any LLM call while an LLM was configured: {len(refused)}, of which "
          f"{len(gate)} hold no dining word at all and {len(other)} are bad input any reader "
          "refuses (a count, diners, a distance, 'or')")
    for text, error in [*gate, *other]:
        print(f"  {text!r}: {error}")


if __name__ == "__main__":
    main()
