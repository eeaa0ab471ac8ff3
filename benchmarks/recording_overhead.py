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
Run: .venv/bin/python benchmarks/recording_overhead.py [--seeds 5] [--task 8]
     [--simulators kinematic2d,mujoco] [--quick]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

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
    ap.add_argument("--task", type=int, default=8)
    ap.add_argument("--simulators", default="kinematic2d,mujoco")
    ap.add_argument("--mcap", action="store_true", help="time a ROS 2 bag (--mcap) instead")
    args = parse_args(ap, {"seeds": 1, "task": 1})
    where = scratch("recordings")
    import rerun

    print(f"{'a ROS 2 bag (--mcap)' if args.mcap else 'a Rerun recording (--rerun)'}; "
          f"rerun-sdk {rerun.__version__}; Task {args.task} x {args.seeds} seeds, LLM-GROP, "
          "the embedded model's answers replayed")
    for name in args.simulators.split(","):
        sim = make_simulator(DEFAULTS.with_values(simulator=name))
        episode(args.task, 0, sim, None)  # warm: imports, the arm's IK model, caches
        plain, recorded, overhead, cpu, sizes = [], [], [], [], []
        for seed in range(args.seeds):
            rrd = where / f"{name}-{seed}.{'mcap' if args.mcap else 'rrd'}"
            if seed % 2:
                (with_s, with_cpu) = episode(args.task, seed, sim, rrd)
                (without_s, without_cpu) = episode(args.task, seed, sim, None)
            else:
                (without_s, without_cpu) = episode(args.task, seed, sim, None)
                (with_s, with_cpu) = episode(args.task, seed, sim, rrd)
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
