"""Figures of issue 36 (the seams between the parts), measured on a source tree.

Prints, for ``--src`` (default: this checkout's ``src/llm_grop``):

* how many places each of a run's defaults is written (M = 25, the weight 40, the 1 MiB
  answer cap, the default simulator's name, the 60 s LLM deadline, 3 navigation
  attempts), by the patterns that write one;
* the largest parameter count of a public function or method (``self`` and ``*args`` /
  ``**kwargs`` not counted), and the five largest;
* every ``getattr``/``hasattr`` call, by file;
* which plugin kinds declare an ``Options`` of their own (the simulator's ``Simulator``,
  the LLM backend's ``BaseLLM``, the method's ``Method``);
* lines of Python and the largest module.

Run it on an older tree to compare: ``git worktree add /tmp/old c269926`` then
``python benchmarks/seams.py --src /tmp/old/src/llm_grop``. ``--quick`` prints the same
figures (the tree is small enough to read whole in well under a second).
"""

from __future__ import annotations

import argparse
import ast
import re
from pathlib import Path

#: Each default of a run, and the patterns of Python that write its value.
DEFAULTS: dict[str, list[str]] = {
    "M = 25": [r"\bm\s*(?::\s*int)?\s*=\s*25\b", r"default=25\b", r"Field\(25\b",
               r"\]\s*=\s*25\b", r"^\s*25,\s*\"Configurations"],
    "weight 40": [r"\bw\s*(?::\s*float)?\s*=\s*40\.0\b", r"default=40\.0",
                  r"^\s*40\.0,\s*\"GROP"],
    "answer cap 1 MiB": [r"1024\s*\*\s*1024", r"1_048_576", r"2\s*\*\*\s*20"],
    "simulator kinematic2d": [r"(?<!name )[=(]\s*\"kinematic2d\"\s*[,)]",
                              r"(?<!name )=\s*\"kinematic2d\"\s*$",
                              r"Field\(\"kinematic2d\"", r"^\s*\"kinematic2d\",\s*\"The"],
    "LLM deadline 60 s": [r"timeout_s\s*(?::\s*float)?\s*=\s*60\.0", r"default=60\.0",
                          r"^\s*60\.0,\s*\"Seconds one LLM"],
    "nav attempts 3": [r"NAV_ATTEMPTS\s*=\s*3\b", r"nav_attempts.*default=3\b",
                       r"^\s*3,\s*\"Attempts per navigation"],
}


def default_places(files: list[Path], root: Path) -> dict[str, list[str]]:
    """The lines (``file:line``) that write each default."""
    found: dict[str, list[str]] = {name: [] for name in DEFAULTS}
    for f in files:
        for k, line in enumerate(f.read_text(encoding="utf-8").splitlines(), 1):
            for name, patterns in DEFAULTS.items():
                if any(re.search(p, line) for p in patterns):
                    found[name].append(f"{f.relative_to(root)}:{k}")
    return found


def public_parameters(files: list[Path], root: Path) -> list[tuple[int, str]]:
    """``(parameter count, name)`` of every public function and method."""
    out = []
    for f in files:
        parts = f.relative_to(root).parts
        if any(part.startswith("_") and part != "__init__.py" for part in parts):
            continue
        tree = ast.parse(f.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef) and node.name.startswith("_"):
                for child in ast.walk(node):
                    child._private = True  # type: ignore[attr-defined]
        for node in ast.walk(tree):
            if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            if node.name.startswith("_") or getattr(node, "_private", False):
                continue
            a = node.args
            names = [x.arg for x in (*a.posonlyargs, *a.args, *a.kwonlyargs)]
            names = [n for n in names if n not in ("self", "cls")]
            module = ".".join(f.relative_to(root.parent).with_suffix("").parts)
            out.append((len(names), f"{module}.{node.name}"))
    return sorted(out, reverse=True)


def probes(files: list[Path], root: Path) -> dict[str, int]:
    """``getattr``/``hasattr`` calls per file."""
    out: dict[str, int] = {}
    for f in files:
        n = len(re.findall(r"\b(?:getattr|hasattr)\(", f.read_text(encoding="utf-8")))
        if n:
            out[str(f.relative_to(root))] = n
    return out


#: Each plugin kind's declaring class, and its module under the package.
KINDS = {"simulator": ("Simulator", "simulation/base.py"),
         "LLM backend": ("BaseLLM", "llm/base.py"),
         "method": ("Method", "methods/base.py")}


def declared_kinds(root: Path) -> dict[str, bool]:
    """Whether each plugin kind's class declares ``Options`` (an assignment, annotation or
    property of that name in its body)."""
    out = {}
    for kind, (cls, module) in KINDS.items():
        tree = ast.parse((root / module).read_text(encoding="utf-8"))
        body = next((n.body for n in ast.walk(tree)
                     if isinstance(n, ast.ClassDef) and n.name == cls), [])
        names = {t.id for n in body if isinstance(n, ast.Assign) for t in n.targets
                 if isinstance(t, ast.Name)}
        names |= {n.target.id for n in body
                  if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)}
        names |= {n.name for n in body if isinstance(n, ast.FunctionDef)}
        out[kind] = "Options" in names
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--src", type=Path,
                        default=Path(__file__).resolve().parent.parent / "src" / "llm_grop")
    parser.add_argument("--quick", action="store_true", help="the same figures (it is quick)")
    args = parser.parse_args()
    root = args.src.resolve()
    files = sorted(p for p in root.rglob("*.py"))
    print(f"== {root}")
    print("places each default is written:")
    for name, where in default_places(files, root).items():
        print(f"  {name:24s} {len(where)}  {' '.join(where)}")
    params = public_parameters(files, root)
    print(f"largest parameter count of a public function: {params[0][0]} ({params[0][1]})")
    for n, name in params[1:5]:
        print(f"  then {n:2d} {name}")
    found = probes(files, root)
    print(f"getattr/hasattr calls: {sum(found.values())} in {len(found)} files")
    for name, n in sorted(found.items(), key=lambda kv: -kv[1]):
        print(f"  {n:2d} {name}")
    kinds = declared_kinds(root)
    print(f"plugin kinds that declare their own Options: {sum(kinds.values())} of {len(kinds)} "
          f"({', '.join(k for k, v in kinds.items() if v) or 'none'})")
    sizes = {f: len(f.read_text(encoding="utf-8").splitlines()) for f in files}
    big = max(sizes, key=lambda f: sizes[f])
    print(f"lines of Python: {sum(sizes.values())} in {len(files)} modules; largest "
          f"{big.relative_to(root)} ({sizes[big]})")


if __name__ == "__main__":
    main()
