"""Shared set-up for the benchmark scripts: the recorded LLM, summary statistics, and the
``--quick`` mode every script has (a tiny case in seconds, what ``tests/test_benchmarks.py``
runs so that no script can rot unnoticed)."""

from __future__ import annotations

import argparse
import contextlib
import math
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
from collections.abc import Iterator, Mapping, Sequence
from http.server import ThreadingHTTPServer
from pathlib import Path
from typing import Any

from llm_grop import make_llm
from llm_grop.llm.base import BackendOptions, CallLog

#: Embedded-model answers for tasks 1-8 x seeds 0-19 and task 8 x seeds 20-49, written by
#: benchmarks/record_embedded.py.
RECORDING = Path(__file__).parent / "data" / "embedded_calls.jsonl"

#: The help text of every script's ``--quick``.
QUICK_HELP = ("a tiny case in a few seconds, figures printed as usual (what the tests run; "
              "the figures mean little)")

#: Scratch directories made for quick runs, removed when the process ends.
_SCRATCH: list[tempfile.TemporaryDirectory[str]] = []


def replay_llm() -> CallLog:
    """The embedded model's recorded answers, replayed (no model needed)."""
    if not RECORDING.exists():
        raise SystemExit(f"{RECORDING} is missing: run benchmarks/record_embedded.py first")
    return make_llm("replay", BackendOptions(replay_path=RECORDING))


def median_p95(values: list[float]) -> tuple[float, float]:
    """Median and 95th percentile (nearest rank) of ``values``."""
    ordered = sorted(values)
    return statistics.median(ordered), ordered[math.ceil(0.95 * len(ordered)) - 1]


def mean_se(values: list[float]) -> tuple[float, float]:
    """Mean and standard error of ``values``."""
    if len(values) < 2:
        return (values[0] if values else math.nan), math.nan
    return statistics.fmean(values), statistics.stdev(values) / math.sqrt(len(values))


def parse_args(parser: argparse.ArgumentParser, quick: Mapping[str, object] | None = None,
               argv: Sequence[str] | None = None) -> argparse.Namespace:
    """``parser``'s arguments, with ``--quick`` added: given it, the values in ``quick``
    (keyed by each option's ``dest``) replace those options' defaults, so an option given
    on the command line still wins. A callable value is called for the value, and only in
    quick mode (a scratch directory is made only when wanted)."""
    parser.add_argument("--quick", action="store_true", help=QUICK_HELP)
    args = parser.parse_args(argv)
    if args.quick and quick:
        parser.set_defaults(**{k: v() if callable(v) else v for k, v in quick.items()})
        args = parser.parse_args(argv)
    return args


def span(text: str) -> list[int]:
    """``"1-3,5"`` -> ``[1, 2, 3, 5]``; :class:`ValueError` for anything else."""
    out: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        out += range(int(lo), int(hi or lo) + 1)
    return out


def chat_server() -> tuple[Any, Any]:
    """The tests' local OpenAI-compatible chat server (``tests/conftest.py``), started on
    127.0.0.1: its state (set ``reply``; ``url`` is its ``/v1`` base URL) and the HTTP
    server (``shutdown()`` stops it)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from conftest import ChatServer, _handler

    state = ChatServer()
    httpd = ThreadingHTTPServer(("127.0.0.1", 0), _handler(state))
    state.url = f"http://127.0.0.1:{httpd.server_address[1]}/v1"
    threading.Thread(target=httpd.serve_forever, args=(0.02,), daemon=True).start()
    return state, httpd


def scratch(name: str) -> Path:
    """A fresh directory, removed when the process ends: where a quick run writes what a
    full run writes into the working tree."""
    tmp = tempfile.TemporaryDirectory(prefix=f"llm-grop-{name}-")
    _SCRATCH.append(tmp)
    return Path(tmp.name)


def bench(out: Path, *options: str, methods: str = "tpra,latp,grop,llm-grop",
          tasks: str = "8", trials: int = 1, workers: int = 1) -> Path:
    """``llm-grop bench`` into ``out`` with the embedded model's recorded answers replayed,
    2D and no pictures unless ``options`` say otherwise (they come last, so they win);
    ``out``."""
    subprocess.run([sys.executable, "-m", "llm_grop", "bench", "--tasks", tasks, "--trials",
                    str(trials), "--methods", methods, "--llm", "replay", "--replay",
                    str(RECORDING), "--workers", str(workers), "--no-images", "--out",
                    str(out), "-q", *options], check=True)
    return out


@contextlib.contextmanager
def quick_bench(*options: str, methods: str = "tpra,latp,grop,llm-grop"
                ) -> Iterator[Path]:
    """A tiny bench (Task 8, one trial, one worker: see :func:`bench`) in a scratch
    directory, for the scripts that read bench results, in quick mode."""
    with tempfile.TemporaryDirectory(prefix="llm-grop-quick-bench-") as tmp:
        yield bench(Path(tmp) / "bench", *options, methods=methods)


@contextlib.contextmanager
def results_dirs(parser: argparse.ArgumentParser, args: argparse.Namespace, *options: str,
                 methods: str = "tpra,latp,grop,llm-grop") -> Iterator[list[Path]]:
    """The bench results directories ``args.dirs`` (a ``nargs="*"`` positional); in quick
    mode without any, a tiny bench's (:func:`quick_bench`); without any otherwise, the
    parser's usage error."""
    if args.dirs:
        yield args.dirs
    elif not args.quick:
        parser.error("the following arguments are required: dirs (or --quick)")
    else:
        with quick_bench(*options, methods=methods) as out:
            yield [out]


def free_port() -> int:
    """A free TCP port on 127.0.0.1."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def start_server(db: Path, *flags: str) -> tuple[subprocess.Popen[bytes], str]:
    """``llm-grop serve`` on a free loopback port, answering from the embedded model's
    recording, with its job database ``db`` and ``flags``: its process and URL, once it
    answers."""
    import os
    import time

    import httpx

    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "llm_grop", "serve", "--llm", "replay", "--replay",
         str(RECORDING), "--db", str(db), "--port", str(port), *flags],
        env=os.environ | {"MUJOCO_GL": "osmesa"}, stderr=subprocess.DEVNULL)
    url = f"http://127.0.0.1:{port}"
    for _ in range(300):
        try:
            if httpx.get(f"{url}/v1/info", timeout=1).status_code == 200:
                return proc, url
        except httpx.HTTPError:
            time.sleep(0.1)
    proc.kill()
    raise SystemExit("the server did not start")


def write_settings(where: Path, request: str, sentences: Sequence[str], seeds: Sequence[int],
                   catalog: Any) -> list[Path]:
    """Example table settings of ``request`` set as the preference ``sentences`` say, one
    per seed, as arrangement JSON files in ``where`` (no LLM is asked: the sentences place
    every object)."""
    import json

    from llm_grop import arrange, arrangement_to_dict
    from llm_grop.arrangement.options import ArrangeOptions

    empty = where / "no_calls.jsonl"
    empty.write_text("", encoding="utf-8")
    out = []
    for seed in seeds:
        shown = arrange(request, seed=seed, catalog=catalog, llm="replay",
                        llm_options=BackendOptions(replay_path=str(empty)),
                        options=ArrangeOptions(preference_pool=tuple(sentences)))
        path = where / f"example{seed}.json"
        path.write_text(json.dumps(arrangement_to_dict(shown.arrangement)), encoding="utf-8")
        out.append(path)
    return out
