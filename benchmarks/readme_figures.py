"""Regenerates the README's experiment figures and says which version produced them.

Runs (or resumes) the benches behind the README's tables into DIR, 2 workers, no pictures,
every LLM answer replayed from the embedded model's recording
(``benchmarks/data/embedded_calls.jsonl``, SmolLM2-135M-Instruct):

* ``2d``: the paper's experiment, Table I's 8 tasks x 20 trials x 4 methods, kinematic2d;
* ``2d-preferences``: the same with ``--preferences benchmarks/data/preferences.yaml``, a
  hand-written file that states the rater's own conventions as preferences: it measures how
  faithfully the pipeline carries stated relations, not an LLM;
* ``2d-preferences-fw0``: LLM-GROP alone, as ``2d-preferences`` with ``--fidelity-weight 0``;
* ``chairs4``: Task 8 x 50 trials, 4 chairs, LLM-GROP with the preferences;
* ``3d``: the paper's experiment in MuJoCo, planning with the belief ``--feasibility auto``
  chooses there (``mujoco``; 27 minutes on 2 cores with version 0.17.0);
* ``3d-default``: the same with ``--feasibility default`` (23 minutes).

It prints each table in the README's layout (mean ± standard error, every figure from the
automatic rater where it is a rating), then the executive's figures of the 3D run.
``--quick`` runs ``2d`` and ``chairs4`` on Task 8 with one trial, one worker, in a scratch
directory.
Run: .venv/bin/python benchmarks/readme_figures.py [--out DIR] [--only 2d,3d,...] [--workers 2]
     [--quick]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

from common import RECORDING, parse_args, scratch
from figure_versions import project_version

HERE = Path(__file__).parent
PREFERENCES = HERE / "data" / "preferences.yaml"
PAPER = ["--tasks", "1-8", "--trials", "20", "--methods", "tpra,latp,grop,llm-grop"]
BENCHES: dict[str, list[str]] = {
    "2d": PAPER,
    "2d-preferences": [*PAPER, "--preferences", str(PREFERENCES)],
    "2d-preferences-fw0": ["--tasks", "1-8", "--trials", "20", "--methods", "llm-grop",
                           "--preferences", str(PREFERENCES), "--fidelity-weight", "0"],
    "chairs4": ["--tasks", "8", "--trials", "50", "--chairs", "4", "--methods", "llm-grop",
                "--preferences", str(PREFERENCES)],
    "3d": [*PAPER, "--simulator", "mujoco"],
    "3d-default": [*PAPER, "--simulator", "mujoco", "--feasibility", "default"],
}
METHODS = ("tpra", "latp", "grop", "llm-grop")


def bench(name: str, out: Path, workers: int = 2, quick: bool = False) -> tuple[dict, float]:
    """Run (or resume) bench ``name`` into ``out/name`` (with ``quick``, on Task 8 with one
    trial); its summary and wall seconds."""
    options = list(BENCHES[name])
    if quick:
        for flag, value in (("--tasks", "8"), ("--trials", "1")):
            options[options.index(flag) + 1] = value
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "llm_grop", "bench", *options, "--llm", "replay",
                    "--replay", str(RECORDING), "--workers", str(workers), "--no-images",
                    "--out", str(out / name), "-q"], check=True)
    return json.loads((out / name / "summary.json").read_text()), time.perf_counter() - t0


def _cell(m: dict, key: str, digits: int) -> str:
    se = m[key]["se"]  # None for a single trial
    return f"{m[key]['mean']:.{digits}f} ± {'-' if se is None else f'{se:.{digits}f}'}"


def table(summaries: dict[str, dict], columns: list[tuple[str, str]]) -> None:
    """Rating, execution time and share of episodes with everything placed, per method,
    for each ``(label, bench)`` column group."""
    head = " | ".join(f"{label}: rating | time (s) | all placed" for label, _ in columns)
    print(f"| method | {head} |")
    print("| --- |" + " ---: |" * (3 * len(columns)))
    for method in METHODS:
        cells = []
        for _, name in columns:
            by = {m["method"]: m for m in summaries[name]["methods"]}
            if method not in by:
                cells += ["-", "-", "-"]
                continue
            m = by[method]
            cells += [_cell(m, "rating", 2), _cell(m, "execution_time_s", 1),
                      f"{100 * m['success_rate']['mean']:.0f} %"]
        print(f"| {method} | " + " | ".join(cells) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("readme-figures"))
    ap.add_argument("--only", default=",".join(BENCHES))
    ap.add_argument("--workers", type=int, default=2)
    args = parse_args(ap, {"out": lambda: scratch("readme-figures"), "only": "2d,chairs4",
                           "workers": 1})
    names = [n for n in args.only.split(",") if n]
    unknown = set(names) - set(BENCHES)
    if unknown:
        raise SystemExit(f"--only: unknown bench {sorted(unknown)}; choose from {list(BENCHES)}")
    summaries, walls = {}, {}
    for name in names:
        summaries[name], walls[name] = bench(name, args.out, args.workers, args.quick)
    # The checkout's version: an editable install's metadata keeps the version it was
    # installed with.
    print(f"\nllm-grop {project_version()}; LLM: the embedded model's answers "
          f"(SmolLM2-135M-Instruct) replayed from {RECORDING.relative_to(HERE.parent)}; "
          f"ratings from the automatic rater")
    for name in names:
        print(f"  {name}: {walls[name]:.0f} s wall this time (resumed benches count only "
              "what was left)")
    if "2d" in summaries:
        cols = [("embedded", "2d")]
        if "2d-preferences" in summaries:
            cols.append(("rater's conventions as preferences", "2d-preferences"))
        print("\nThe paper's experiment, 2D:")
        table(summaries, cols)
    if "3d" in summaries:
        print("\nThe paper's experiment, 2D against 3D (MuJoCo):")
        cols = [("2D", "2d")] if "2d" in summaries else []
        cols.append(("3D", "3d"))
        if "3d-default" in summaries:
            cols.append(("3D, default belief", "3d-default"))
        table(summaries, cols)
    for name, what in (("2d-preferences-fw0", "LLM-GROP with the preferences and "
                        "--fidelity-weight 0"),
                       ("chairs4", "Task 8 x 50, 4 chairs, LLM-GROP with the preferences")):
        if name in summaries:
            (m,) = summaries[name]["methods"]
            ok = round(m["success_rate"]["mean"] * m["success_rate"]["n"])
            print(f"\n{what}: time {_cell(m, 'execution_time_s', 1)} s, rating "
                  f"{_cell(m, 'rating', 2)}, everything placed in {ok} of "
                  f"{m['success_rate']['n']} episodes")
    if "3d" in summaries:
        print()
        subprocess.run([sys.executable, str(HERE / "executive.py"), "results",
                        str(args.out / "2d"), str(args.out / "3d")]
                       if "2d" in summaries else
                       [sys.executable, str(HERE / "executive.py"), "results",
                        str(args.out / "3d")], check=True)


if __name__ == "__main__":
    main()
