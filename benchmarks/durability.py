"""Issue 27's figures: how llm-grop holds up under faults and abuse.

* LLM calls against hostile servers on loopback: one that trickles its answer a byte at a
  time, one that answers 429 with ``Retry-After: 50``, one that sends a 30 MB answer;
  each call's wall time against ``--timeout 3``, and what it ended with.
* The rating site's peak resident memory while a 50 MiB chunked body is sent to
  ``/api/session`` unauthenticated.
* ``llm-grop bench`` interrupted (Ctrl-C or SIGTERM) at 20 random moments, start-up
  included: how many printed a traceback, and the exit statuses.

    python benchmarks/durability.py [--timeout 3] [--body-mib 50] [--interrupts 20]
        [--latest 4] [--quick]
"""

from __future__ import annotations

import argparse
import json
import random
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import httpx
from common import RECORDING, parse_args

from llm_grop.errors import LLMError, LLMTransient
from llm_grop.llm.base import BackendOptions, SamplingParams
from llm_grop.llm.openai_backend import OpenAILLM

ANSWER = json.dumps({"choices": [{"message": {"content": "Place the plate in the center."}}]})


def hostile(mode: str) -> ThreadingHTTPServer:
    """A chat-completions server that misbehaves in ``mode``, on a free loopback port."""
    class Handler(BaseHTTPRequestHandler):
        protocol_version = "HTTP/1.1"

        def do_POST(self) -> None:
            self.rfile.read(int(self.headers.get("content-length", "0")))
            if mode == "retry-after":
                body = b'{"error": {"message": "slow down"}}'
                self.send_response(429)
                self.send_header("retry-after", "50")
            else:
                body = (ANSWER.encode() if mode == "trickle" else json.dumps(
                    {"choices": [{"message": {"content": "x" * 30_000_000}}]}).encode())
                self.send_response(200)
            self.send_header("content-type", "application/json")
            self.send_header("content-length", str(len(body)))
            self.end_headers()
            try:
                if mode == "trickle":
                    for k in range(len(body)):
                        self.wfile.write(body[k:k + 1])
                        self.wfile.flush()
                        time.sleep(1.0)
                else:
                    self.wfile.write(body)
            except OSError:
                pass

        def log_message(self, *args: object) -> None:
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def llm_calls(timeout_s: float) -> None:
    print(f"LLM calls with --timeout {timeout_s:g} --retries 2 (the openai backend):")
    for mode in ("trickle", "retry-after", "huge"):
        server = hostile(mode)
        llm = OpenAILLM(BackendOptions(base_url=f"http://127.0.0.1:{server.server_port}/v1",
                                       timeout_s=timeout_s, max_retries=2))
        t0 = time.monotonic()
        try:
            llm.complete("hi", SamplingParams(seed=0))
            ending = "answered"
        except (LLMError, LLMTransient) as exc:
            ending = str(exc).split(": ", 1)[1][:110]
        print(f"  {mode:12s} {time.monotonic() - t0:6.2f} s  {ending}")
        server.shutdown()


def site_memory(mib: int) -> None:
    sys.path.insert(0, str(Path(__file__).parent))
    from ratings_load import server_process, synthetic_study

    with tempfile.TemporaryDirectory() as tmp:
        db = Path(tmp) / "study.db"
        synthetic_study(db, 8)
        with server_process(db) as (url, proc):
            def peak() -> int:
                for line in Path(f"/proc/{proc.pid}/status").read_text().splitlines():
                    if line.startswith("VmHWM:"):
                        return int(line.split()[1]) // 1024
                return 0

            before = peak()

            def chunks():
                for _ in range(mib):
                    yield b"A" * (1024 * 1024)

            try:
                status = httpx.post(f"{url}api/session", content=chunks(), timeout=60,
                                    headers={"content-type": "application/json"}).status_code
            except httpx.HTTPError as exc:
                status = type(exc).__name__
            print(f"rating site, {mib} MiB chunked body to /api/session: answer {status}; peak "
                  f"resident memory {before} MB before, {peak()} MB after")


def interrupts(count: int = 20, latest_s: float = 4.0) -> None:
    rng = random.Random(27)
    codes: Counter = Counter()
    tracebacks = 0
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(count):
            after = rng.uniform(0.02, latest_s)
            sig = signal.SIGTERM if k % 5 == 4 else signal.SIGINT
            proc = subprocess.Popen(
                [sys.executable, "-m", "llm_grop", "bench", "--tasks", "1", "--trials", "2",
                 "--workers", "2", "--llm", "replay", "--replay", str(RECORDING), "--out",
                 f"{tmp}/b{k}", "--no-images", "-q"], stderr=subprocess.PIPE,
                stdout=subprocess.DEVNULL)
            time.sleep(after)
            proc.send_signal(sig)
            _, err = proc.communicate(timeout=120)
            tracebacks += b"Traceback" in err
            codes[(sig.name, proc.returncode)] += 1
    print(f"bench interrupted at {count} random moments (0-{latest_s:g} s): {tracebacks} "
          f"printed a traceback; exit statuses {dict(codes)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--timeout", type=float, default=3.0, help="the LLM calls' timeout, s")
    ap.add_argument("--body-mib", type=int, default=50, help="the body sent to the site, MiB")
    ap.add_argument("--interrupts", type=int, default=20, help="benches interrupted")
    ap.add_argument("--latest", type=float, default=4.0,
                    help="the latest moment a bench is interrupted, s after its start")
    args = parse_args(ap, {"timeout": 0.5, "body_mib": 2, "interrupts": 2, "latest": 1.0})
    llm_calls(args.timeout)
    site_memory(args.body_mib)
    interrupts(args.interrupts, args.latest)


if __name__ == "__main__":
    main()
