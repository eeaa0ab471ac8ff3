"""How faithfully the executed plans keep the stated geometry: realised minus stated gaps.

Reads each bench results directory's ``trials.jsonl`` and, for one method's plans (the
chosen configurations), prints the distribution of realised-minus-stated gaps (every
relation with a stated gap, and the origin's distance from the diner's edge) in
centimetres: median, 95th percentile and maximum of the signed error and of its size, and
the share within the sampler's tolerance; then the same gaps as executed, measured
between the objects where they ended up (the ``final`` arrangement) when both were placed.
Run: .venv/bin/python benchmarks/fidelity.py bench-preferences [--method llm-grop]
     .venv/bin/python benchmarks/fidelity.py --quick   (a tiny bench of its own)
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from common import parse_args, results_dirs

from llm_grop.arrangement.fidelity import GAP_TOLERANCE_M, realised_gap_m
from llm_grop.arrangement.predicates import Footprint
from llm_grop.world.arrangement import Placement

#: The preferences of ``--quick``'s bench, which state gaps (as the README's bench does).
PREFERENCES = Path(__file__).parent / "data" / "preferences.yaml"


def errors_cm(path: Path, method: str) -> tuple[list[float], list[float], list[float]]:
    """Signed errors, centimetres: the planned relations' gaps, the planned diners'
    distances, and the gaps as executed."""
    gaps, edges, executed = [], [], []
    for line in (path / "trials.jsonl").read_text().splitlines():
        row = json.loads(line)
        if row["method"] != method or not row.get("plan"):
            continue
        chosen = row["plan"]["fidelity"]["chosen"]
        gaps += [100 * g["error_m"] for g in chosen["gaps"] or ()]
        if chosen["edge_stated_m"] is not None:
            edges.append(100 * (chosen["edge_realised_m"] - chosen["edge_stated_m"]))
        final = {o["name"]: placement(o) for o in row["final"]["objects"]}
        for g in chosen["gaps"] or ():
            s, r = final.get(g["subject"]), final.get(g["reference"])
            if s is None or r is None:
                continue
            got = realised_gap_m(g["relation"], g["stated_m"], s.x, s.y,
                                 Footprint.of_placement(s), r.x, r.y, Footprint.of_placement(r))
            executed.append(100 * (float(got) - g["stated_m"]))
    return gaps, edges, executed


def placement(o: dict) -> Placement:
    """A final object of a trial row as a placement."""
    return Placement(o["name"], o["x"], o["y"], o["yaw"], o["shape"], tuple(o["size"]))


def _line(name: str, values: list[float]) -> str:
    if not values:
        return f"  {name}: none"
    v = np.asarray(values)
    size = np.abs(v)
    within = float(np.mean(size <= 100 * GAP_TOLERANCE_M + 1e-6))
    return (f"  {name} (n={v.size}): realised - stated median {np.median(v):+.2f} cm, "
            f"p95 {np.percentile(v, 95):+.2f} cm, max {v.max():+.2f} cm, min {v.min():+.2f} cm; "
            f"|error| median {np.median(size):.2f} cm, p95 {np.percentile(size, 95):.2f} cm, "
            f"max {size.max():.2f} cm; within ±{100 * GAP_TOLERANCE_M:g} cm: {within:.1%}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="*", type=Path)
    ap.add_argument("--method", default="llm-grop")
    args = parse_args(ap)
    with results_dirs(ap, args, "--preferences", str(PREFERENCES), methods=args.method) as dirs:
        for d in dirs:
            gaps, edges, executed = errors_cm(d, args.method)
            print(f"{d} ({args.method}), planned (the chosen configurations):")
            print(_line("gaps between objects", gaps))
            print(_line("distance from the diner's edge", edges))
            print(_line("all", gaps + edges))
            print("executed (where the objects ended up):")
            print(_line("gaps between objects", executed))


if __name__ == "__main__":
    main()
