"""What the rating tests share besides fixtures: the admin token, and benchmark scripts
loaded as modules."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]
RECORDING = ROOT / "benchmarks" / "data" / "embedded_calls.jsonl"
ADMIN = "test-admin-token-0123456789"


def load_benchmark(name: str) -> ModuleType:
    """A script under benchmarks/ as a module (the load test shares its driver); its
    directory is on the path, as when it runs, for the helpers it shares."""
    if str(ROOT / "benchmarks") not in sys.path:
        sys.path.insert(0, str(ROOT / "benchmarks"))
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module
