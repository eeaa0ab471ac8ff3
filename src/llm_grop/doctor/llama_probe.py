"""Run by ``llm-grop doctor`` as a script in a process of its own, because a llama.cpp
built for instructions this CPU lacks can kill the process that loads it: imports
llama-cpp-python, without loading a model, and prints one JSON object, ``version`` and
``system_info`` (llama.cpp's list of the CPU features it was compiled for), or ``error``."""

from __future__ import annotations

import json
from typing import Any


def main() -> None:
    """Import llama_cpp and print what it was built for."""
    result: dict[str, Any] = {}
    try:
        import llama_cpp

        result["version"] = str(llama_cpp.__version__)
        info = llama_cpp.llama_print_system_info()
        result["system_info"] = info.decode("utf-8", "replace") if isinstance(info, bytes) \
            else str(info)
    except Exception as exc:  # noqa: BLE001 - every failure is the finding to report
        result["error"] = f"{type(exc).__name__}: {' '.join(str(exc).split())}"
    print(json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
