"""Record the embedded model's answers for the paper's tasks, for offline replay.

Runs the arrangement (paper §III-A, §III-B) of each task and seed on the embedded
SmolLM2 model and appends every LLM call to a JSONL file that `--llm replay` reads.
Episodes (`llm-grop run`, the benchmarks) with the same task and seed then replay
these answers exactly, without the model. Tasks and seeds already in the file are
skipped, so an interrupted recording can be resumed. With ``--fill``, every task and
seed is run again, answering from the file where it can and asking the model only for
calls the file lacks (a question added in a later version), which are appended.
``--llm replay`` asks a recording (``--replay FILE``) instead of the model: ``--quick``
records task 1, seed 0 that way into a scratch file, then fills it in.
Run: .venv/bin/python benchmarks/record_embedded.py --tasks 1-8 --seeds 0-19 \
        --out benchmarks/data/embedded_calls.jsonl [--fill] [--quick]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from common import RECORDING, parse_args, scratch, span

from llm_grop import BackendOptions, arrange, make_llm
from llm_grop.errors import LLMGropError, ReplayMissing
from llm_grop.llm.base import LLM, BaseLLM, SamplingParams
from llm_grop.llm.record import LLMCallRecord, append_record
from llm_grop.llm.registry import create_llm
from llm_grop.llm.replay import ReplayLLM


class FillIn(BaseLLM):
    """Answers from a record file, and for a call the file lacks from the backend ``live``
    (a name, by default the embedded model, or a backend; ``None``: none, the call stays
    missing), appending its answer to the file unless ``write`` is false. ``filled``
    counts the calls ``live`` answered."""

    backend = "embedded"

    def __init__(self, path: Path, live: str | LLM | None = "embedded",
                 options: BackendOptions | None = None, *, write: bool = True) -> None:
        self.path, self.write = path, write
        self.replay = ReplayLLM(BackendOptions(replay_path=str(path)))
        self.model = self.replay.model
        self.live = create_llm(live, options or BackendOptions()) if isinstance(live, str) \
            else live
        self.filled = 0

    def complete(self, prompt: str, params: SamplingParams, grammar: str | None = None
                 ) -> LLMCallRecord:
        try:
            return self.replay.complete(prompt, params, grammar)
        except ReplayMissing:
            if self.live is None:
                raise
            record = self.live.complete(prompt, params, grammar)
            if self.write:
                append_record(self.path, record)
            self.filled += 1
            return record


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", default="1-8")
    ap.add_argument("--seeds", default="0-19")
    ap.add_argument("--out", type=Path, default=Path("benchmarks/data/embedded_calls.jsonl"))
    ap.add_argument("--fill", action="store_true",
                    help="answer from the file, asking the model only for missing calls")
    ap.add_argument("--llm", default="embedded", choices=("embedded", "replay"),
                    help="what answers: the model, or a recording (--replay)")
    ap.add_argument("--replay", type=Path, default=RECORDING, help="the recording to replay")
    args = parse_args(ap, {"tasks": "1", "seeds": "0", "llm": "replay",
                           "out": lambda: scratch("record") / "calls.jsonl"})
    live = BackendOptions(replay_path=args.replay)
    if args.fill:
        fill(args.tasks, args.seeds, args.out, args.llm, live)
        return
    record(args.tasks, args.seeds, args.out, args.llm, live)
    if args.quick:
        fill(args.tasks, args.seeds, args.out, args.llm, live)  # the other path too


def fill(tasks: str, seeds: str, out: Path, backend: str, options: BackendOptions) -> None:
    """Every task and seed again, answered from ``out`` and by ``backend`` for a call ``out``
    lacks (appended to it)."""
    filler = FillIn(out, backend, options)
    for task in span(tasks):
        for seed in span(seeds):
            try:
                arrange(task=task, llm=make_llm(filler), seed=seed)
            except LLMGropError as exc:
                print(f"task {task} seed {seed}: {exc}")
    print(json.dumps({"filled": filler.filled}))


def record(tasks: str, seeds: str, out: Path, backend: str, options: BackendOptions) -> None:
    """Each task and seed not done yet (``out``'s ``.done`` file), recorded into ``out``
    from ``backend``."""
    done_file = out.with_suffix(".done")
    done = set(done_file.read_text().split()) if done_file.exists() else set()
    llm = make_llm(backend, options, record=out)
    for task in span(tasks):
        for seed in span(seeds):
            key = f"{task}:{seed}"
            if key in done:
                continue
            llm.calls.clear()
            t0 = time.perf_counter()
            try:
                result = arrange(task=task, llm=llm, seed=seed)
                rels = len(result.arrangement.relations)
                status = f"{rels} relation(s)"
            except LLMGropError as exc:
                status = f"failed: {exc}"
            with done_file.open("a") as f:
                f.write(key + "\n")
            print(json.dumps({"task": task, "seed": seed, "calls": len(llm.calls),
                              "seconds": round(time.perf_counter() - t0, 1),
                              "status": status}), flush=True)


if __name__ == "__main__":
    main()
