"""How often the embedded model's Template 1 answers are consistent.

Over the paper's 8 tasks x 3 seeds: the fraction consistent on the first
attempt, and after re-prompting (within the default 3 attempts). Optionally
records every call for `--llm replay`. ``--llm replay`` replays a recording of the model
instead (by default ``benchmarks/data/embedded_calls.jsonl``; what ``--quick`` does, with
one seed).
Run: .venv/bin/python benchmarks/consistency_rate.py [--seeds 3] [--record calls.jsonl]
     [--llm embedded|replay] [--replay FILE] [--quick]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from common import RECORDING, parse_args

from llm_grop import BackendOptions, arrange, make_llm
from llm_grop.errors import LLMGropError


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--record", default=None)
    ap.add_argument("--llm", default="embedded", choices=("embedded", "replay"))
    ap.add_argument("--replay", type=Path, default=RECORDING, help="the recording to replay")
    args = parse_args(ap, {"seeds": 1, "llm": "replay"})
    llm = make_llm(args.llm, BackendOptions(replay_path=args.replay), record=args.record)
    first = after = runs = 0
    for task in range(1, 9):
        for seed in range(args.seeds):
            runs += 1
            llm.calls.clear()
            try:
                result = arrange(task=task, llm=llm, seed=seed)
            except LLMGropError as exc:
                print(f"task {task} seed {seed}: failed: {exc}")
                continue
            attempts = result.attempts
            ok_first = bool(attempts) and attempts[0].consistent
            ok_after = any(a.consistent for a in attempts)
            first += ok_first
            after += ok_after
            rels = "; ".join(f"{r.subject} {r.relation} {r.reference or 'table'}"
                             for r in result.arrangement.relations)
            print(f"task {task} seed {seed}: attempts {len(attempts)}, first consistent "
                  f"{ok_first}, consistent after re-prompting {ok_after}, "
                  f"dropped {len(result.dropped)} | {rels}")
    print(f"consistent on the first attempt: {first}/{runs} = {first / runs:.2f}")
    print(f"consistent after re-prompting (<= 3 attempts): {after}/{runs} = {after / runs:.2f}")


if __name__ == "__main__":
    main()
