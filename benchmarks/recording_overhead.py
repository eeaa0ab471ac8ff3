"""What a Rerun recording costs: its size and the wall-time overhead of ``--rerun`` (and,
with ``--mcap``, of a ROS 2 bag).

Runs Task 8 (``--task``) with LLM-GROP (the embedded model's recorded answers, 1 chair) on
seeds 0..N-1 in each simulator, each seed twice, without and with a recording, in turns
(which goes first alternates from seed to seed, so that a slow spell of the machine falls
on both). Prints, per simulator, the median wall time of a whole episode (arrange, plan,
execute, the recording written) without and with the recording, the median of each
seed's overhead in per cent of its episode without, the same for the process's CPU time
(its threads included: Rerun encodes and writes on threads of its own; on a machine
other work shares, CPU time varies less than wall time), and the recordings' sizes.
With ``--repeat K`` each seed's pair is run K times and each side's fastest run counts,
as ``timeit`` does: interference from other work only ever adds time, so the minimum is
the closest to what the episode itself costs.
Run: .venv/bin/python benchmarks/recording_overhead.py [--seeds 5] [--repeat 1] [--task 8]
     [--simulators kinematic2d,mujoco] [--sim-option KEY=VALUE ...] [--mcap] [--quick]
(``--sim-option record_cameras=[robot] --simulators mujoco``: with camera frames)
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import yaml
from common import parse_args, replay_llm, scratch

from llm_grop.api import run
from llm_grop.assembly import make_simulator
from llm_grop.settings import DEFAULTS


def episode(task: int, seed: int, sim: object, out: Path | None) -> tuple[float, float]:
    """Wall and CPU seconds of one episode, recorded to ``out`` when given (a Rerun
    recording or a ROS 2 bag, by its suffix)."""
    kind = {".rrd": "rerun", ".mcap": "mcap"}.get(out.suffix) if out is not None else None
    t0, c0 = time.perf_counter(), time.process_time()
    run(task=task, seed=seed, llm=replay_llm(), simulator=sim,
        **({kind: str(out)} if kind is not None and out is not None else {}))
    return time.perf_counter() - t0, time.process_time() - c0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=1,
                    help="run each seed's pair K times; the fastest of each side counts")
    ap.add_argument("--task", type=int, default=8)
    ap.add_argument("--simulators", default="kinematic2d,mujoco")
    ap.add_argument("--sim-option", action="append", default=[], metavar="KEY=VALUE",
                    help="an option of each simulator, as `llm-grop run --sim-option`")
    ap.add_argument("--mcap", action="store_true", help="time a ROS 2 bag (--mcap) instead")
    args = parse_args(ap, {"seeds": 1, "task": 1, "repeat": 1})
    where = scratch("recordings")
    import rerun

    print(f"{'a ROS 2 bag (--mcap)' if args.mcap else 'a Rerun recording (--rerun)'}; "
          f"rerun-sdk {rerun.__version__}; Task {args.task} x {args.seeds} seeds, "
          f"fastest of {args.repeat} run(s) each, LLM-GROP, the embedded model's answers "
          f"replayed{'; ' + ', '.join(args.sim_option) if args.sim_option else ''}")
    for name in args.simulators.split(","):
        options = {k: yaml.safe_load(v) for k, v in (o.split("=", 1) for o in args.sim_option)}
        sim = make_simulator(DEFAULTS.with_values(simulator=name, sim_options=options))
        episode(args.task, 0, sim, None)  # warm: imports, the arm's IK model, caches
        plain, recorded, overhead, cpu, sizes = [], [], [], [], []
        for seed in range(args.seeds):
            rrd = where / f"{name}-{seed}.{'mcap' if args.mcap else 'rrd'}"
            runs: dict[bool, list[tuple[float, float]]] = {False: [], True: []}
            for k in range(args.repeat):
                first = bool((seed + k) % 2)
                for recording in (first, not first):
                    runs[recording].append(episode(args.task, seed, sim,
                                                   rrd if recording else None))
            without_s, without_cpu = (min(r[i] for r in runs[False]) for i in (0, 1))
            with_s, with_cpu = (min(r[i] for r in runs[True]) for i in (0, 1))
            plain.append(without_s)
            recorded.append(with_s)
            overhead.append(100 * (with_s - without_s) / without_s)
            cpu.append(100 * (with_cpu - without_cpu) / without_cpu)
            sizes.append(rrd.stat().st_size / 1e6)
            print(f"  {name} seed {seed}: {without_s:.2f} s without, {with_s:.2f} s with "
                  f"({overhead[-1]:+.1f} %); CPU {without_cpu:.2f} s, {with_cpu:.2f} s "
                  f"({cpu[-1]:+.1f} %); {sizes[-1]:.2f} MB")
        print(f"{name}: episode wall time median {statistics.median(plain):.2f} s without, "
              f"{statistics.median(recorded):.2f} s with a recording; overhead median "
              f"{statistics.median(overhead):+.1f} % (min {min(overhead):+.1f}, max "
              f"{max(overhead):+.1f}); CPU time overhead median "
              f"{statistics.median(cpu):+.1f} % (min {min(cpu):+.1f}, max {max(cpu):+.1f}); "
              f"recording {statistics.median(sizes):.2f} MB median ({min(sizes):.2f} to "
              f"{max(sizes):.2f})")


if __name__ == "__main__":
    main()
