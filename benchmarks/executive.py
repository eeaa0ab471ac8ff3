"""The executive's figures: lines of execution logic, and what bench results say about
success, failures by reason, re-grasps and re-places.

* ``lines [--before REV]``: code lines (no blank lines, comments or docstrings) of the
  execution logic in the working tree (the ``execution`` package) and at ``REV``, where
  each simulator carried its own copy (``Kinematic2D.execute`` and ``Run``, the MuJoCo
  ``Episode``, ``MujocoSimulator.execute`` and the place judgement in manipulation).
* ``results DIR...``: for each bench results directory (``trials.jsonl``) and method:
  episodes, all placed, failed attempts per episode by reason, mean execution time,
  re-grasps (a pick right after a place that let go out of place), disturbed objects and
  how many were put back, and false successes: episodes reported successful where an
  object is missing from the final table, tilted more than 0.35 rad, on another support
  than planned or more than 3 cm from its planned place (tilt is only known from 0.9.0).

Run: .venv/bin/python benchmarks/executive.py lines --before 26cf4ac
     .venv/bin/python benchmarks/executive.py results bench-3d-vs-2d/kinematic2d ...
     .venv/bin/python benchmarks/executive.py --quick   (both: results of a tiny bench)
"""

from __future__ import annotations

import argparse
import ast
import json
import math
import statistics
import subprocess
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

from common import parse_args, results_dirs

ROOT = Path(__file__).resolve().parents[1]
#: The last revision before the executive.
BEFORE_REV = "26cf4ac"
#: Where each simulator's copy of the execution logic lived before the executive:
#: ``(file, top-level names)``, an empty tuple for the whole file.
BEFORE = (("src/llm_grop/simulation/kinematic2d.py", ("Kinematic2D.execute", "Run")),
          ("src/llm_grop/simulation/mujoco/episode.py", ()),
          ("src/llm_grop/simulation/mujoco/simulator.py", ("MujocoSimulator.execute",)),
          ("src/llm_grop/simulation/mujoco/manipulation.py", ("_judged",)))
AFTER = (("src/llm_grop/execution/executive.py", ()),
         ("src/llm_grop/execution/judge.py", ()),
         ("src/llm_grop/execution/policy.py", ()))
#: Every file that executes plans, policy and primitives together, before and after.
_SIM = "src/llm_grop/simulation"
FILES_BEFORE = (f"{_SIM}/kinematic2d.py", f"{_SIM}/mujoco/episode.py",
                f"{_SIM}/mujoco/session.py", f"{_SIM}/mujoco/simulator.py",
                f"{_SIM}/mujoco/manipulation.py")
FILES_AFTER = (f"{_SIM}/kinematic2d.py", f"{_SIM}/mujoco/session.py",
               f"{_SIM}/mujoco/simulator.py", f"{_SIM}/mujoco/manipulation.py",
               *(path for path, _ in AFTER))
#: The tolerances success is checked against, independently of the executive's own.
MAX_TILT_RAD, MAX_OFFSET_M = 0.35, 0.03


def code_lines(source: str, names: tuple[str, ...]) -> int:
    """Lines of code of ``names`` (``Class.method`` or top-level) in ``source``, or of the
    whole file: blank lines, comments and docstrings left out."""
    tree = ast.parse(source)
    doc_lines: set[int] = set()
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                and isinstance(getattr(body[0], "value", None), ast.Constant) \
                and isinstance(body[0].value.value, str):
            doc_lines |= set(range(body[0].lineno, (body[0].end_lineno or 0) + 1))
    spans: list[tuple[int, int]] = []
    if not names:
        spans = [(1, len(source.splitlines()))]
    for name in names:
        outer, _, inner = name.partition(".")
        for node in tree.body:
            if getattr(node, "name", None) != outer:
                continue
            if inner:
                node = next(n for n in node.body if getattr(n, "name", None) == inner)  # type: ignore[attr-defined]
            spans.append((node.lineno, node.end_lineno or node.lineno))
    lines = source.splitlines()
    return sum(1 for a, b in spans for k in range(a, b + 1)
               if k not in doc_lines and lines[k - 1].strip()
               and not lines[k - 1].strip().startswith("#"))


def lines(before: str) -> None:
    if subprocess.run(["git", "cat-file", "-e", f"{before}^{{commit}}"], cwd=ROOT,
                      capture_output=True).returncode != 0:
        raise SystemExit(f"lines: revision {before} is not in this clone (a shallow one?)")
    old = sum(code_lines(_show(before, path), names) for path, names in BEFORE)
    new = sum(code_lines((ROOT / path).read_text(), names) for path, names in AFTER)
    print(f"lines of execution logic: {old} at {before} (two copies, one per simulator), "
          f"{new} now (one executive)")
    old_all = sum(code_lines(_show(before, path), ()) for path in FILES_BEFORE)
    new_all = sum(code_lines((ROOT / path).read_text(), ()) for path in FILES_AFTER)
    print(f"lines of the simulators' execution files and the executive together: {old_all} at "
          f"{before}, {new_all} now")


def _show(rev: str, path: str) -> str:
    return subprocess.run(["git", "show", f"{rev}:{path}"], cwd=ROOT, check=True,
                          capture_output=True, text=True).stdout


def _false_success(row: dict[str, Any]) -> bool:
    if not row.get("success"):
        return False
    planned = {o["name"]: o for o in row["planned"]["objects"]}
    final = {o["name"]: o for o in row["final"]["objects"]}
    for name, p in planned.items():
        f = final.get(name)
        if f is None or (f.get("tilt_rad") or 0.0) > MAX_TILT_RAD or f.get("on") != p.get("on") \
                or math.hypot(f["x"] - p["x"], f["y"] - p["y"]) > MAX_OFFSET_M:
            return True
    return False


def _regrasps_and_replaces(steps: list[dict[str, Any]]) -> tuple[int, int, int]:
    regrasps = disturbed = put_back = 0
    for k, s in enumerate(steps):
        before = [t for t in steps[:k] if t.get("object") == s.get("object")]
        if s["action"] == "pick" and before and before[-1]["action"] == "place" \
                and before[-1].get("reason") in ("slid", "wrong_support"):
            regrasps += 1
        if s.get("reason") == "disturbed":
            disturbed += 1
            put_back += any(t["action"] == "place" and t["ok"]
                            and t.get("object") == s.get("object") for t in steps[k + 1:])
    return regrasps, disturbed, put_back


def results(dirs: list[Path]) -> None:
    for d in dirs:
        rows = [json.loads(line) for line in (d / "trials.jsonl").read_text().splitlines()
                if line.strip()]
        rows = [r for r in rows if r.get("status") == "ok"]
        by_method: dict[str, list[dict[str, Any]]] = defaultdict(list)
        for r in rows:
            by_method[r["method"]].append(r)
        print(f"\n{d} ({rows[0]['simulator'] if rows else '?'}, {len(rows)} episodes)")
        totals = Counter()  # type: ignore[var-annotated]
        for method, rs in sorted(by_method.items()):
            reasons: Counter[str] = Counter()
            extra = Counter()  # type: ignore[var-annotated]
            for r in rs:
                for s in r["steps"]:
                    if not s["ok"]:
                        reasons[s.get("reason") or "(none)"] += 1
                g, dist, back = _regrasps_and_replaces(r["steps"])
                extra.update(regrasps=g, disturbed=dist, put_back=back,
                             false_successes=int(_false_success(r)))
            totals.update(extra)
            n = len(rs)
            per = ", ".join(f"{k} {v / n:.2f}" for k, v in reasons.most_common())
            print(f"  {method:<9} all placed {sum(r['success'] for r in rs)}/{n}; "
                  f"time {statistics.fmean(r['execution_time_s'] for r in rs):.1f} s; "
                  f"failed attempts per episode {sum(reasons.values()) / n:.2f} ({per or '-'}); "
                  f"re-grasps {extra['regrasps']}, disturbed {extra['disturbed']} "
                  f"(put back {extra['put_back']}), false successes "
                  f"{extra['false_successes']}")
        print(f"  all methods: false successes {totals['false_successes']}, re-grasps "
              f"{totals['regrasps']}, disturbed {totals['disturbed']} (put back "
              f"{totals['put_back']})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="what")
    sub.add_parser("lines").add_argument("--before", default=BEFORE_REV)
    sub.add_parser("results").add_argument("dirs", nargs="*", type=Path)
    args = parse_args(ap)
    if args.quick and args.what is None:  # both figures; the results of a tiny bench
        try:
            lines(BEFORE_REV)
        except SystemExit as exc:
            print(exc)
        args.what, args.dirs = "results", []
    if args.what == "lines":
        lines(args.before)
    elif args.what == "results":
        with results_dirs(ap, args) as dirs:
            results(dirs)
    else:
        ap.error("choose lines or results (or --quick)")


if __name__ == "__main__":
    main()
