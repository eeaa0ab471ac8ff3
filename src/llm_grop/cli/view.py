"""``llm-grop view FILE.rrd``: an episode's Rerun recording in Rerun's viewer.

Where a display exists (``DISPLAY`` or ``WAYLAND_DISPLAY``) the native viewer opens it;
otherwise, or with ``--web``, Rerun's bundled web viewer serves it over HTTP on
127.0.0.1 (another address only with ``--host``), and the command prints the address to
open and runs until Ctrl-C. Both are Rerun's own ``rerun`` program from the ``[viz]``
extra, started as a child process that dies with this one.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import quote

import click

from llm_grop.cli.options import EPILOG
from llm_grop.errors import BadInput

#: The first bytes of every Rerun recording (``RRF2`` since Rerun 0.23, ``RRF0``/``RRF1``
#: before).
RRD_MAGIC = b"RRF"
#: Seconds the web viewer may take to answer on its port before the command gives up.
START_S = 60.0
#: Loopback, where the web viewer listens unless told otherwise.
LOOPBACK = "127.0.0.1"


@click.command(epilog=EPILOG)
@click.argument("recording", metavar="FILE.rrd", type=click.Path(path_type=Path))
@click.option("--web", is_flag=True,
              help="Serve Rerun's web viewer even where a display exists.")
@click.option("--host", default=LOOPBACK, show_default=True,
              help="The address the web viewer and its data server listen on; any other "
                   "than loopback lets other machines see the recording.")
@click.option("--port", type=click.IntRange(0, 65535), default=0,
              help="The web viewer's HTTP port [default: a free one].")
def view(recording: Path, web: bool, host: str, port: int) -> None:
    """Open an episode's Rerun recording (run --rerun, bench --rerun, the service's
    episode.rrd) in Rerun's viewer: the native one where a display exists, else the web
    viewer on 127.0.0.1."""
    check_recording_file(recording)
    binary = rerun_binary()
    if not web and (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise click.exceptions.Exit(_wait(_start([str(binary), str(recording)])))
    http = port or free_port(host)
    data = free_port(host)
    child = _start([str(binary), str(recording), "--web-viewer", "--bind", host,
                    "--web-viewer-port", str(http), "--port", str(data)], quiet=True)
    try:
        _await_port(child, host, http)
        shown = f"[{host}]" if ":" in host else host
        source = quote(f"rerun+http://{shown}:{data}/proxy", safe="")
        click.echo(f"Rerun web viewer: http://{shown}:{http}/?url={source}")
        click.echo("Ctrl-C stops it.", err=True)
    except BaseException:
        _stop(child)
        raise
    raise click.exceptions.Exit(_wait(child))


def check_recording_file(path: Path) -> None:
    """:class:`BadInput` unless ``path`` is a readable Rerun recording (by its first
    bytes), said before anything starts."""
    try:
        with open(path, "rb") as handle:
            magic = handle.read(len(RRD_MAGIC))
    except FileNotFoundError:
        raise BadInput(f"{path}: no such file") from None
    except IsADirectoryError:
        raise BadInput(f"{path}: is a directory; give a recording (.rrd)") from None
    except OSError as exc:
        raise BadInput(f"{path}: {exc.strerror or exc}") from None
    if magic != RRD_MAGIC:
        raise BadInput(f"{path}: not a Rerun recording (an .rrd file from run --rerun, "
                       "bench --rerun or the service)")


def rerun_binary() -> Path:
    """Rerun's ``rerun`` program from the ``[viz]`` extra (``$RERUN_CLI_PATH`` if set, as
    Rerun's own launcher honours); :class:`BadInput` naming the extra when it is
    missing."""
    import importlib.util

    from llm_grop.recording.episode import EXTRAS

    if os.environ.get("RERUN_CLI_PATH"):
        return Path(os.environ["RERUN_CLI_PATH"])
    spec = importlib.util.find_spec("rerun_cli")
    folders = list(spec.submodule_search_locations or []) if spec is not None else []
    found = [Path(f) / ("rerun.exe" if sys.platform.startswith("win") else "rerun")
             for f in folders]
    if not found or not found[0].is_file():
        raise BadInput(f"view: needs the optional {EXTRAS['rerun']}")
    return found[0]


def free_port(host: str) -> int:
    """A TCP port free on ``host`` now."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def _start(argv: list[str], quiet: bool = False) -> subprocess.Popen[bytes]:
    from llm_grop.processes import die_with_parent

    out = subprocess.DEVNULL if quiet else None
    return subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=out, stderr=out,
                            preexec_fn=die_with_parent)  # noqa: PLW1509 - only prctl


def _await_port(child: subprocess.Popen[bytes], host: str, port: int) -> None:
    """Wait until the web viewer answers on ``port``; :class:`BadInput` when it ended."""
    deadline = time.monotonic() + START_S
    while time.monotonic() < deadline:
        if child.poll() is not None:
            raise BadInput(f"view: Rerun's web viewer stopped at once (status "
                           f"{child.returncode}); is port {port} on {host} free?")
        try:
            with socket.create_connection((host, port), timeout=0.5):
                return
        except OSError:
            time.sleep(0.1)
    raise BadInput(f"view: Rerun's web viewer did not answer on {host}:{port} within "
                   f"{START_S:.0f} s")


def _wait(child: subprocess.Popen[bytes]) -> int:
    """The child's exit status; Ctrl-C (or SIGTERM) stops it first."""
    try:
        return child.wait()
    except BaseException:
        _stop(child)
        raise


def _stop(child: subprocess.Popen[bytes]) -> None:
    if child.poll() is None:
        child.terminate()
        try:
            child.wait(timeout=5)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()
