"""Re-measures every README figure in one go, resumably: the driver of a minor release's
re-measurement (the policy ``figure_versions.py`` checks).

``STEPS`` is the table: one entry per command that makes figures (a step may serve several),
with the README paragraphs it serves (a phrase of each, so that the table survives edits),
its kind (``deterministic``: seeded rows, ratings, pictures; ``timing``: wall times,
latencies, throughput, which need a quiet machine), and its exact command, reconstructed from
the paragraph that quotes the figure and from the script's own ``Run:`` line. Where the
README does not say an argument, the entry's note says what was assumed.

Each step's stdout and stderr go to ``DIR/NAME.txt``, its exit status and wall time to
``DIR/NAME.json``; a step whose ``.json`` says it succeeded, with this version and the same
command, is skipped on the next call (``--redo NAME`` runs it again). Steps run one at a
time: deterministic ones first, then timing ones, then those that read another step's results
(``needs``). Steps marked ``writes`` change the working tree by design (``docs/`` pictures,
README's ``run`` example); their files must be rewritten for the step to count as done.
Afterwards it prints, for every figure of ``figure_versions.inventory``, the steps that serve
it, and flags a figure no step serves or a phrase that matches no figure (exit status 1).
``--quick``: the list, the coverage check and one short step (``rater-agreement``), run
twice into a scratch directory (the second call skips it).
Run: .venv/bin/python benchmarks/readme_remeasure.py [--out DIR] [--only a,b] [--skip a,b]
     [--kind timing|deterministic] [--redo NAME] [--list] [--quick]
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from common import parse_args, scratch
from figure_versions import Figure, inventory, paragraphs, project_version

ROOT = Path(__file__).resolve().parent.parent
KINDS = ("deterministic", "timing")
#: The embedded model's recorded answers, as the README's commands replay them.
REPLAY = "--llm replay --replay benchmarks/data/embedded_calls.jsonl"
RUN_3D = f"llm-grop run --task 8 {REPLAY} --simulator mujoco"
FIGURES = "python benchmarks/readme_figures.py --out {out}/readme-figures --workers 2 --only"
FIT = "python benchmarks/fit_profile.py --seeds 20 --workers 2"
PAPER = "The paper's whole experiment in 3D"


@dataclass(frozen=True)
class Step:
    """One command that makes README figures.

    ``serves``: a phrase of each README paragraph (or a picture's ``docs/`` path) it makes;
    ``command``: shell words, ``python`` and ``llm-grop`` standing for this interpreter and
    its package, ``{out}`` for the output directory, run from the repository root (or
    ``cwd``); ``writes``: files of the working tree it rewrites; ``clears``: directories
    removed first, so that its wall time is a whole run's; ``needs``: steps whose results it
    reads; ``minutes``: how long it took last time, where known."""

    name: str
    kind: str
    serves: tuple[str, ...]
    command: str
    writes: tuple[str, ...] = ()
    env: tuple[tuple[str, str], ...] = ()
    cwd: str = ""
    clears: tuple[str, ...] = ()
    needs: tuple[str, ...] = ()
    minutes: float | None = None
    note: str = ""


def _d(name: str, serves: tuple[str, ...], command: str, **more: Any) -> Step:
    """A deterministic step."""
    return Step(name, "deterministic", serves, command, **more)


def _t(name: str, serves: tuple[str, ...], command: str, **more: Any) -> Step:
    """A timing step (it needs a quiet machine)."""
    return Step(name, "timing", serves, command, **more)


STEPS: tuple[Step, ...] = (
    _d("family-table", ("Set the table for six with a dinner plate",
                        "With `--capacity 4` in this room the planner chooses no trip"),
       "python benchmarks/family_table.py --seeds 20 --jobs 2",
       note="--jobs is not in the README; the script says figures do not depend on it"),
    _d("family-kitchen", ("With `--capacity 4` in this room the planner chooses no trip",),
       "python benchmarks/family_table.py --seeds 20 --scene benchmarks/data/kitchen_apart.yaml"
       " --jobs 2", note="the README names only --scene; 20 seeds (its default) as the table's"
       " x/20 say"),
    _d("family-grop-100", ("The issue's target, every object placed in 90 % of episodes",),
       "python benchmarks/family_table.py --seeds 100 --methods grop --capacities 1 --jobs 2",
       note="GROP over 100 seeds (about 3 minutes)"),
    _t("family-planning", ("**Planning time as the table grows**",),
       "python benchmarks/family_planning.py", note="about 1.5 minutes"),
    _t("learn-time", ("**Learning from 3 examples**",),
       "python benchmarks/learn_time.py", note="a few seconds"),
    _d("style-learning", ("**The style benchmark**", "Seen objects keep the style every time",
                          "**The usual style learned from 2 examples**",
                          "Within 0.1 on seven tasks"),
       "python benchmarks/style_learning.py", note="the stand-in's rows and the paper's "
       "tasks (about 3 minutes)"),
    _d("style-learning-embedded", ("**The style benchmark**",
                                   "Seen objects keep the style every time"),
       "python benchmarks/style_learning.py --llm embedded --paper-seeds 1 --tasks 1",
       note="the embedded model's rows, run live (about 15 minutes)"),
    _d("hard-scenes", ("**The hard-scene suite**",),
       "python benchmarks/hard_scenes.py --seeds 10", note="the stand-in's rows"),
    _d("hard-scenes-embedded", ("**The hard-scene suite**",),
       "python benchmarks/hard_scenes.py --seeds 10 --llm embedded",
       note="the embedded model's rows, run live (about 10 minutes)"),
    _d("feedback-paper", ("**On the paper's tasks** (`benchmarks/feedback_paper.py`",
                          "In the same runs (`feedback_paper.py`"),
       "python benchmarks/feedback_paper.py", note="the embedded model live for what its "
       "recording lacks (about 3 minutes)"),
    _d("feedback-paper-stand-in", ("A local server answering as a capable model would "
                                   "(`feedback_paper.py --llm stand-in`",),
       "python benchmarks/feedback_paper.py --llm stand-in", note="about 1 minute"),
    _d("family-mujoco", ("In MuJoCo (`family_table.py --simulator mujoco",),
       "python benchmarks/family_table.py --simulator mujoco --methods grop --capacities 1,4"
       " --seeds 10 --jobs 2", note="six diners in physics (about 30 minutes on 2 cores)"),
    _d("family-embedded", ('"Set the table for six with a dinner plate',),
       "python benchmarks/family_table.py --seeds 20 --methods embedded --capacities 1",
       note="the embedded model run live (about 17 minutes); its column of the first table"),
    _d("friction-grasp", ("**A grasp must hold**",),
       "python benchmarks/friction_grasp.py --grasp fix,friction"),
    _d("mujoco-pictures", ("docs/mujoco_table.png", "docs/mujoco_room.png",
                           "(Task 8, seed 0, the episode above",
                           "this episode (seed 0) succeeds"),
       f"{RUN_3D} --table-image docs/mujoco_table.png --room-image docs/mujoco_room.png",
       writes=("docs/mujoco_table.png", "docs/mujoco_room.png"),
       note="its console is the seed-0 episode the 3D run paragraph quotes"),
    _d("mujoco-diner-picture", ("docs/mujoco_diner.png", "(Task 8, seed 0, the episode above"),
       f"{RUN_3D} --camera diner --table-image docs/mujoco_diner.png",
       writes=("docs/mujoco_diner.png",)),
    _d("run-3d-seed8", ("this episode (seed 0) succeeds",),
       f"{RUN_3D} --seed 8 --json {{out}}/run-3d-seed8.json",
       note="the README's command also writes table.png, room.png and episode.mp4, no figures:"
       " left out"),
    _d("mujoco-stacking", ("`benchmarks/mujoco_stacking.py`",),
       "python benchmarks/mujoco_stacking.py --seeds 20"),
    _d("fit-mujoco-fitted", ("Predicted against measured on Task 8",),
       f"{FIT} --simulator mujoco --feasibility mujoco", minutes=5,
       note="minutes estimated from the README's wall column"),
    _d("fit-2d-truth-fitted", ("`--truth mujoco` makes the 2D simulator draw",),
       f"{FIT} --simulator kinematic2d --truth mujoco --feasibility mujoco"),
    _d("baseline-draws", ("TPRA and GROP draw each object's centre from a Gaussian",),
       "python benchmarks/baseline_draws.py --seeds 20"),
    _d("rater-agreement", ("`llm-grop rate FILE.json` rates any arrangement JSON",),
       "python benchmarks/rater_agreement.py"),
    _d("relation-meaning", ("**What a relation means geometrically**",),
       "python -m pytest tests/arrangement/test_relation_meaning.py -q"
       " --hypothesis-show-statistics"),
    _d("rerun-browser", ("docs/rerun_web.png", "`tests/recording/test_view_browser.py` makes"),
       "python -m pytest tests/recording/test_view_browser.py -q",
       env=(("LLM_GROP_SCREENSHOTS", "docs"),), writes=("docs/rerun_web.png",)),
    _d("ratings-browser", ("A rater opens the site, types their invite code",
                           "docs/ratings/rating.png"),
       "python -m pytest tests/ratings/test_browser.py -q",
       env=(("LLM_GROP_SCREENSHOTS", "docs/ratings"),),
       writes=tuple(f"docs/ratings/{n}.png" for n in ("guidelines", "rating", "rating-phone",
                                                      "report"))),
    _d("playground-browser", ("**The playground** at `/`",),
       "python -m pytest tests/service/test_playground_browser.py -q",
       env=(("LLM_GROP_SCREENSHOTS", "docs/serve"),),
       writes=tuple(f"docs/serve/{n}.png" for n in ("arrange_desktop", "arrange_phone",
                                                    "run_mujoco"))),
    _d("doctor", ("`llm-grop doctor` checks, without the network",), "llm-grop doctor",
       note="prints this machine's state; exits 1 when a needed part is missing"),
    _t("readme-run", ("docs/run.png", "(The main job's `run.png`", "Printed by "
                      "`benchmarks/readme_run.py`", "the mug goes *on top of the mug lid*"),
       "python benchmarks/readme_run.py", writes=("docs/run.png", "README.md"),
       note="rows and picture are seeded; the console's planning time is a wall time"),
    _t("arrange-live", ("(Printed by `llm-grop arrange` with the embedded model run live",
                        "`table.png` is a top-down picture, to scale"),
       'llm-grop arrange "set the table with a dinner plate, a dinner fork and a dinner knife"'
       " --json table.json --image table.png --no-cache", cwd="{out}/arrange-live",
       env=(("COLUMNS", "100"), ("NO_COLOR", "1")),
       note="the embedded model live, no model server running (--llm auto must choose it);"
       " --no-cache stands for the README's empty cache, COLUMNS=100 for its wrapping"),
    _t("figures-2d", ("On the paper's benchmark, LLM-GROP", "runs Table I's 8 tasks × 20",
                      "(Four of the twelve rows", "(Mean ± standard error over 160 trials",
                      PAPER),
       f"{FIGURES} 2d,2d-preferences,2d-preferences-fw0,chairs4",
       clears=tuple(f"{{out}}/readme-figures/{b}" for b in ("2d", "2d-preferences",
                                                           "2d-preferences-fw0", "chairs4")),
       note="the README's 28 s is the 2d bench's own wall line"),
    _t("figures-3d", (PAPER, "runs Table I's 8 tasks × 20", "Both simulators run the same",
                      "this episode (seed 0) succeeds"),
       f"{FIGURES} 3d", clears=("{out}/readme-figures/3d",), minutes=27),
    _t("figures-3d-default", (PAPER,), f"{FIGURES} 3d-default",
       clears=("{out}/readme-figures/3d-default",), minutes=23),
    _t("render-3d", ("The 3D pictures are made for raters",),
       "python benchmarks/render_3d.py --frames 30"),
    _t("mujoco-episode", ("`benchmarks/mujoco_episode.py`",),
       "python benchmarks/mujoco_episode.py --seeds 10 --task 8 --feasibility default"),
    _t("fit-mujoco-default", ("`benchmarks/fit_profile.py` runs Task 8",
                              "Predicted against measured on Task 8"),
       f"{FIT} --simulator mujoco --feasibility default", minutes=5,
       note="minutes estimated from the README's wall column"),
    _t("fit-2d", ("`benchmarks/fit_profile.py` runs Task 8",),
       f"{FIT} --simulator kinematic2d --feasibility default"),
    _t("fit-2d-truth", ("`benchmarks/fit_profile.py` runs Task 8",),
       f"{FIT} --simulator kinematic2d --truth mujoco --feasibility default",
       note="the paragraph's default belief is assumed for its --truth mujoco rows too"),
    _t("recording-overhead", ("What a recording costs",),
       "python benchmarks/recording_overhead.py --seeds 10 --repeat 3", minutes=7,
       note="minutes estimated from the README's episode wall times"),
    _t("recording-cameras", ("What a recording costs",),
       "python benchmarks/recording_overhead.py --seeds 10 --repeat 2 --simulators mujoco"
       " --sim-option record_cameras=[robot]", minutes=5),
    _t("recording-mcap", ("What a recording costs",),
       "python benchmarks/recording_overhead.py --seeds 10 --repeat 3 --mcap", minutes=7),
    _t("ray-loopback", ("**Where trials run.**",),
       "python benchmarks/ray_loopback.py --tasks 1,2,3,4 --trials 3 --repeats 3"),
    _t("sweep-scale", ("Measured (`benchmarks/sweep_scale.py`",),
       "python benchmarks/sweep_scale.py --out {out}/sweep-scale --trials 20 --workers 2"
       " --executors local,ray", minutes=19),
    _t("ratings-load", ("Load (`benchmarks/ratings_load.py`",),
       "python benchmarks/ratings_load.py --raters 20 --ratings 2000"),
    _t("phrasings-replay", ("it reads none of the 255 requests", "How well requests are read",
                            "The fast path never read a request"),
       "python benchmarks/phrasings.py --llm replay"
       " --replay benchmarks/data/phrasings_embedded.jsonl",
       note="the recording is not re-recorded (--record rewrites a data file); the replayed"
       " call's 0.3 ms is a wall time"),
    _t("phrasings-live", ("How well requests are read", "The fast path never read a request"),
       "python benchmarks/phrasings.py --llm embedded --limit 40"),
    _t("serve-load", ("Measured with `benchmarks/serve_load.py`",),
       "python benchmarks/serve_load.py --workers 2 --requests 60"),
    _t("stalled-connections", ("Slow clients (`benchmarks/stalled_connections.py`",),
       "python benchmarks/stalled_connections.py --connections 300 --watch 60",
       note="the 'before the read deadlines (2ae1355)' figure is an old checkout's: not rerun"),
    _t("service-uptime", ("Measured with `benchmarks/service_uptime.py`",),
       "python benchmarks/service_uptime.py",
       note="the 0.15.0 figures are an old checkout's: not rerun"),
    _t("llm-deadlines", ("**Hostile LLM servers**",),
       "python benchmarks/llm_deadlines.py --timeout 5 --cap 60",
       note="the 0.15.0 figures are an old checkout's: not rerun"),
    _d("figures-tables", (PAPER, "Both simulators run the same", "(Four of the twelve rows",
                          "(Mean ± standard error over 160 trials"),
       "python benchmarks/readme_figures.py --out {out}/readme-figures --workers 2",
       needs=("figures-2d", "figures-3d", "figures-3d-default"),
       note="all six benches resumed: prints every table and the executive's 3D figures; its"
       " wall lines are near 0, the benches' own are in figures-2d/3d/3d-default"),
    _d("fig3-picture", ("docs/fig3_rating_vs_time.png",),
       "cp {out}/readme-figures/2d/fig3_rating_vs_time.png docs/fig3_rating_vs_time.png",
       writes=("docs/fig3_rating_vs_time.png",), needs=("figures-2d",)),
    _d("table-picture", ("docs/table.png",),
       "cp {out}/arrange-live/table.png docs/table.png", writes=("docs/table.png",),
       needs=("arrange-live",)),
    _d("paper-claims", ("(Mean ± standard error over 160 trials",),
       "python benchmarks/paper_claims.py {out}/readme-figures/2d"
       " {out}/readme-figures/2d-preferences", needs=("figures-2d",)),
    _d("fidelity", ("(Mean ± standard error over 160 trials",),
       "python benchmarks/fidelity.py {out}/readme-figures/2d-preferences",
       needs=("figures-2d",)),
)
BY_NAME = {s.name: s for s in STEPS}


def ordered(steps: list[Step]) -> list[Step]:
    """Deterministic steps, then timing ones, then those that read others' results (in the
    table's order, which lists a step after those it needs)."""
    return sorted(steps, key=lambda s: (bool(s.needs), KINDS.index(s.kind)))


def argv(step: Step, out: Path) -> list[str]:
    """``step``'s command as run: ``python`` and ``llm-grop`` made this interpreter."""
    words = shlex.split(step.command.replace("{out}", str(out)))
    head = {"python": [sys.executable], "llm-grop": [sys.executable, "-m", "llm_grop"]}
    return [*head.get(words[0], words[:1]), *words[1:]]


def describe(step: Step, out: Path) -> str:
    """``step`` in a few lines for ``--list``."""
    extra = [f"about {step.minutes:g} min" if step.minutes else "",
             f"WRITES {', '.join(step.writes)}" if step.writes else "",
             f"needs {', '.join(step.needs)}" if step.needs else "",
             " ".join(f"{k}={v}" for k, v in step.env)]
    lines = [f"{step.name} ({step.kind}{''.join(f'; {e}' for e in extra if e)})",
             f"    $ {step.command.replace('{out}', str(out))}"
             + (f"   (in {step.cwd.replace('{out}', str(out))})" if step.cwd else ""),
             *(f"    serves: {p}" for p in step.serves)]
    return "\n".join(lines + ([f"    note: {step.note}"] if step.note else []))


def coverage(readme: str) -> tuple[list[tuple[Figure, list[str]]], list[str]]:
    """Each figure of ``readme`` with the steps that serve it, and the table's phrases that
    match no figure (a paragraph rewritten or removed)."""
    text = dict(paragraphs(readme))
    figures = inventory(readme)
    flat = {f.line: " ".join(text[f.line].split()) for f in figures}
    found, stale = [], []
    for figure in figures:
        found.append((figure, [s.name for s in STEPS
                               if any(" ".join(p.split()) in flat[figure.line]
                                      for p in s.serves)]))
    for step in STEPS:
        stale += [f"{step.name}: '{p}'" for p in step.serves
                  if not any(" ".join(p.split()) in block for block in flat.values())]
    return found, stale


def report_coverage() -> bool:
    """Print which steps serve each README figure; whether every figure is served and every
    phrase matches one."""
    found, stale = coverage((ROOT / "README.md").read_text(encoding="utf-8"))
    print(f"\nREADME figures ({len(found)}) and the steps that serve them:")
    for figure, names in found:
        print(f"  line {figure.line:5d}  {figure.what[:58]:58s} "
              f"{', '.join(names) or '** NO STEP SERVES IT **'}")
    missed = [f for f, names in found if not names]
    for phrase in stale:
        print(f"  ** phrase matches no README figure: {phrase}")
    print(f"{len(found) - len(missed)} of {len(found)} figures served by the {len(STEPS)} "
          f"steps; {len(stale)} stale phrases")
    return not missed and not stale


def done_before(step: Step, out: Path, version: str) -> dict | None:
    """The record of ``step``'s earlier success with this version and command, if any."""
    record = out / f"{step.name}.json"
    if not record.is_file():
        return None
    try:
        got = json.loads(record.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError):
        return None
    same = got.get("argv") == argv(step, out) and got.get("version") == version
    return got if got.get("exit") == 0 and same else None


def run_step(step: Step, out: Path, version: str) -> dict:
    """Run ``step``, its output into ``out/NAME.txt``; its record, also written to
    ``out/NAME.json``."""
    for where in step.clears:
        shutil.rmtree(where.replace("{out}", str(out)), ignore_errors=True)
    cwd = Path(step.cwd.replace("{out}", str(out))) if step.cwd else ROOT
    cwd.mkdir(parents=True, exist_ok=True)
    words = argv(step, out)
    env = os.environ | {"MUJOCO_GL": os.environ.get("MUJOCO_GL", "osmesa"),
                        **{k: v for k, v in step.env}}
    if env.get("PYTHONPATH"):  # the steps run elsewhere than this process may have
        env["PYTHONPATH"] = os.pathsep.join(str(Path(p).resolve())
                                            for p in env["PYTHONPATH"].split(os.pathsep) if p)
    started, t0 = datetime.now(UTC), time.perf_counter()
    with (out / f"{step.name}.txt").open("w", encoding="utf-8") as log:
        log.write(f"$ {shlex.join(words)}\n")
        log.flush()
        code = subprocess.run(words, cwd=cwd, env=env, stdout=log,
                              stderr=subprocess.STDOUT).returncode
    wall = time.perf_counter() - t0
    stale = [w for w in step.writes if not (ROOT / w).is_file()
             or (ROOT / w).stat().st_mtime < started.timestamp() - 1]
    record = {"name": step.name, "kind": step.kind, "argv": words, "exit": code,
              "wall_s": round(wall, 1), "started": started.isoformat(timespec="seconds"),
              "version": version, "not_written": stale}
    if code == 0 and stale:
        record["exit"] = "did not write " + ", ".join(stale)
    (out / f"{step.name}.json").write_text(json.dumps(record, indent=1) + "\n",
                                           encoding="utf-8")
    return record


def run_all(steps: list[Step], out: Path, redo: set[str]) -> list[tuple[Step, str, float]]:
    """Run ``steps`` in order, one at a time, each unless done before; each step's state
    and wall seconds (Ctrl-C ends the run with what is done)."""
    out.mkdir(parents=True, exist_ok=True)
    version, states, ok = project_version(), [], set()
    for k, step in enumerate(steps, 1):
        head = f"[{k}/{len(steps)}] {step.name} ({step.kind})"
        before = None if step.name in redo else done_before(step, out, version)
        if before is not None:
            ok.add(step.name)
            states.append((step, "skipped (done before)", before["wall_s"]))
            print(f"{head}: done before in {before['wall_s']} s, skipped", flush=True)
            continue
        missing = [n for n in step.needs
                   if n not in ok and done_before(BY_NAME[n], out, version) is None]
        if missing:
            states.append((step, f"not run: needs {', '.join(missing)}", 0.0))
            print(f"{head}: not run, needs {', '.join(missing)}", flush=True)
            continue
        print(f"{head}{f', about {step.minutes:g} min' if step.minutes else ''}: "
              f"{step.command.replace('{out}', str(out))}", flush=True)
        try:
            record = run_step(step, out, version)
        except KeyboardInterrupt:
            print(f"\ninterrupted during {step.name}: it runs again next time", flush=True)
            states.append((step, "interrupted", 0.0))
            break
        good = record["exit"] == 0
        ok |= {step.name} if good else set()
        states.append((step, "ok" if good else f"FAILED ({record['exit']})", record["wall_s"]))
        print(f"    {'ok' if good else 'FAILED'} in {record['wall_s']} s -> "
              f"{out / step.name}.txt", flush=True)
    return states


def names(value: str, flag: str) -> set[str]:
    """The step names of a comma-separated ``flag`` value; exits naming an unknown one."""
    got = {n for n in value.split(",") if n}
    if unknown := sorted(got - set(BY_NAME)):
        raise SystemExit(f"{flag}: unknown step {', '.join(unknown)}; --list lists them")
    return got


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("readme-remeasure"))
    ap.add_argument("--only", default="", help="comma-separated steps (default: all)")
    ap.add_argument("--skip", default="", help="comma-separated steps to leave out")
    ap.add_argument("--kind", choices=KINDS, help="only steps of this kind")
    ap.add_argument("--redo", action="append", default=[],
                    help="run this step (comma-separated steps) even if done before")
    ap.add_argument("--list", action="store_true", help="list the steps; run nothing")
    args = parse_args(ap, {"out": lambda: scratch("readme-remeasure"),
                           "only": "rater-agreement"})
    out = args.out.resolve()
    chosen = names(args.only, "--only") or set(BY_NAME)
    chosen -= names(args.skip, "--skip")
    redo = names(",".join(args.redo), "--redo")
    steps = ordered([s for s in STEPS if s.name in chosen
                     and (args.kind is None or s.kind == args.kind)])
    if args.list or args.quick:
        for step in ordered(list(STEPS)) if args.quick else steps:
            print(describe(step, out))
    covered = report_coverage()
    if args.list:
        sys.exit(0 if covered else 1)
    print(f"\nllm-grop {project_version()}: {len(steps)} steps into {out}", flush=True)
    states = run_all(steps, out, redo)
    if args.quick:  # the same step again: done, so skipped
        states = run_all(steps, out, redo)
    print("\nSummary:")
    for step, state, wall in states:
        print(f"  {step.name:22s} {step.kind:13s} {state:34s} {wall:8.1f} s")
    failed = [s.name for s, state, _ in states if not state.startswith(("ok", "skipped"))]
    print(f"{len(states) - len(failed)} of {len(states)} steps done"
          + (f"; not done: {', '.join(failed)}" if failed else ""))
    if not covered:
        print("some README figures are served by no step, or a phrase is stale (above)")
    sys.exit(1 if failed or not covered else 0)


if __name__ == "__main__":
    main()
