"""The ``llm-grop`` console script: the command line (:mod:`llm_grop.cli`), with one line
and no traceback for every interrupt, whenever it comes.

It imports nothing heavy itself, so a Ctrl-C while the command line is still loading is
answered like any other, once it has loaded (a second one at once). SIGTERM is taken as an
interrupt (exit status 143; 130 for Ctrl-C); once the command has ended, a late Ctrl-C or
SIGTERM changes nothing.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import signal
import sys
import threading
from types import FrameType

from llm_grop.errors import interrupted

#: Exit statuses of an interrupted command: 128 plus the signal's number.
INTERRUPTED = 130
TERMINATED = 143


def main() -> int:
    """Run the command line; its exit status."""
    received: list[int] = []
    loading, deferred = True, False

    def interrupt(signum: int, frame: FrameType | None) -> None:
        nonlocal deferred
        if _in_cleanup(frame):
            # Raised here, in a finaliser or a weak reference's callback, the interrupt
            # would be printed as "Exception ignored" and lost; it is sent again, to land
            # where the command can take it.
            threading.Timer(0.02, os.kill, (os.getpid(), signum)).start()
            return
        received.append(signum)
        if loading and not deferred:
            # Raised inside an extension module's start (numpy's, under shapely's), the
            # interrupt is printed there as a traceback and comes out as an ImportError
            # of no cause: the first is answered once the command line has loaded.
            deferred = True
            return
        raise KeyboardInterrupt  # SIGTERM stops the command as Ctrl-C does, rows saved

    signal.signal(signal.SIGINT, interrupt)
    signal.signal(signal.SIGTERM, interrupt)
    try:
        from llm_grop.cli import main as cli_main

        loading = False
        if deferred:
            raise KeyboardInterrupt
        code = cli_main(signalled=lambda: bool(received))
    except (KeyboardInterrupt, ImportError) as exc:  # before the command line could take it
        if not interrupted(exc):
            raise
        sys.stderr.write("llm-grop: interrupted\n")
        code = INTERRUPTED
    finally:
        # The command has ended: a late signal must not turn its result into a traceback.
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
    code = TERMINATED if code == INTERRUPTED and signal.SIGTERM in received else code
    if code in (INTERRUPTED, TERMINATED):
        _exit(code)
    return code


def _in_cleanup(frame: FrameType | None) -> bool:
    """Whether ``frame`` runs a finaliser or a weak reference's callback, where Python
    prints an exception and carries on instead of raising it (the import system's
    module-lock callback, ``_get_module_lock.<locals>.cb``, is one)."""
    while frame is not None:
        module = frame.f_globals.get("__name__")
        if frame.f_code.co_name == "__del__" or module in ("weakref", "_weakrefset") or (
                module in ("_frozen_importlib", "importlib._bootstrap")
                and frame.f_code.co_name == "cb"):
            return True
        frame = frame.f_back
    return False


def _exit(code: int) -> None:
    """End the process with ``code`` now, its exit handlers run and its output flushed.

    An interrupt that came while the command line was still loading its modules sometimes
    has CPython end the process with SIGINT at exit (status -2, measured in 4 of 16
    tries), over the status the command returned; ending here keeps 130 or 143.
    """
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


if __name__ == "__main__":
    sys.exit(main())
