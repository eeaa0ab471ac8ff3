"""Requests in people's own words: which objects each is read as.

Reads every phrasing of benchmarks/data/phrasings.yaml three ways and prints the objects
read, against those a person means:

- ``matcher``: the catalog matcher alone (``llm=None``), which refuses what it cannot read;
- ``llm``: the matcher plus an LLM for the chunks it cannot read: the embedded model
  (``--llm embedded``, recording with ``--record``), or a recording (``--llm replay
  --replay FILE``);
- ``key``: the matcher plus a hand-written answer key (``answer_key`` in the YAML) in
  the LLM's place, which shows what the pipeline does with a model that answers well.
  It is not a model's output.

Run: .venv/bin/python benchmarks/phrasings.py --llm embedded \
        --record benchmarks/data/phrasings_embedded.jsonl
     .venv/bin/python benchmarks/phrasings.py --llm replay \
        --replay benchmarks/data/phrasings_embedded.jsonl
"""

from __future__ import annotations

import argparse
import re
from collections import Counter
from pathlib import Path
from typing import Any

import yaml

from llm_grop import BackendOptions, Catalog, make_llm, understand
from llm_grop.errors import LLMGropError
from llm_grop.llm.base import CallLog, SamplingParams
from llm_grop.llm.record import LLMCallRecord

DATA = Path(__file__).parent / "data" / "phrasings.yaml"
_CHUNK = re.compile(r'Which objects does "(.*)" ask the robot')


class AnswerKey:
    """Answers the items question from a hand-written key: chunk text -> answer."""

    backend = "key"
    model = "hand-written answer key"

    def __init__(self, key: dict[str, str]) -> None:
        self.key = key

    def complete(self, prompt: str, params: SamplingParams, grammar: str | None = None
                 ) -> LLMCallRecord:
        m = _CHUNK.search(prompt)
        answer = self.key.get(m.group(1), "none") if m else "none"
        return LLMCallRecord(self.backend, self.model, prompt, answer, 0.0, seed=params.seed)


def _read(text: str, catalog: Catalog, llm: CallLog | None, seed: int
          ) -> tuple[str, Counter[str] | None]:
    """``(what was read, kinds of the first diner's setting)`` or the error."""
    try:
        request = understand(text, catalog=catalog, llm=llm, seed=seed)
    except LLMGropError as exc:
        return f"error: {exc}", None
    kinds = Counter(it.kind for it in request.items if it.diner in (None, 0))
    rels = "; ".join(f"{r.subject} {r.relation} {r.reference or 'table'}"
                     for r in request.relations)
    diners = f" x{request.diners} diners" if request.diners > 1 else ""
    shown = ", ".join(f"{n} {k}" if n > 1 else k for k, n in kinds.items())
    return f"{shown}{diners}{f' [{rels}]' if rels else ''}", kinds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--llm", default="embedded", choices=("embedded", "replay", "openai"))
    parser.add_argument("--replay", type=Path)
    parser.add_argument("--record", type=Path)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if args.record is not None and args.record.exists():
        args.record.unlink()  # a fresh recording of this run's calls
    data: dict[str, Any] = yaml.safe_load(DATA.read_text(encoding="utf-8"))
    catalog = Catalog.load(use_env=False)
    llm = make_llm(args.llm, BackendOptions(replay_path=args.replay), record=args.record)
    key = CallLog(AnswerKey(data["answer_key"]))
    exact = Counter[str]()
    for k, case in enumerate(data["phrasings"], 1):
        want = Counter(case["objects"])
        print(f"{k:2d}. {case['text']}")
        for label, log in (("matcher", None), (args.llm, llm), ("key", key)):
            shown, kinds = _read(case["text"], catalog, log, args.seed)
            ok = kinds == want
            exact[label] += ok
            print(f"    {label:8s} {'ok ' if ok else '-- '}{shown}")
    n = len(data["phrasings"])
    print(f"\nexactly the objects meant, of {n} phrasings: " + ", ".join(
        f"{label} {exact[label]}" for label in ("matcher", args.llm, "key")))
    print(f"LLM calls: {args.llm} {len(llm.calls)}, "
          f"{sum(c.latency_s for c in llm.calls):.1f} s; key {len(key.calls)}")


if __name__ == "__main__":
    main()
