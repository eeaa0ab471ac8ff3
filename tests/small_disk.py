"""A small disk of its own for a server under test: a tmpfs of a given size, mounted in a
private mount namespace (``unshare -rm``, a user namespace, so no root is needed where the
kernel allows one), which the test fills, empties and makes read-only while the server
runs on it.

:class:`SmallDisk` starts this file as a script inside the namespace. The script mounts
the tmpfs over a directory (only the namespace sees it there) and then takes commands on
stdin, one a line, answering each with one line on stdout: ``start`` (a JSON command line
and a log file: the process is started inside, its pid answered), ``run`` (the same, its
exit status answered once it ends), ``fill`` (a file takes
the disk's last byte), ``free``, ``ro PATH`` (a read-only bind mount over the file PATH)
and ``rw PATH`` (that mount taken away again).
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

FILLER = ".filler"


def unavailable() -> str | None:
    """Why a small disk cannot be made here (``None``: it can)."""
    missing = [tool for tool in ("unshare", "mount", "umount") if shutil.which(tool) is None]
    if missing:
        return f"needs {', '.join(missing)} (util-linux)"
    done = subprocess.run(["unshare", "-rm", "sh", "-c", "mount -t tmpfs -o size=64k tmpfs "
                           "/tmp"], capture_output=True, text=True)
    if done.returncode != 0:
        return (f"cannot mount a tmpfs in a user namespace here (unshare -rm: "
                f"{done.stderr.strip()[:200]}); needs user namespaces or root")
    return None


class SmallDisk:
    """A tmpfs of ``size_kib`` KiB over the directory ``where``, in a namespace of its own
    (a context manager: on leaving it, whatever runs inside is stopped and the disk goes)."""

    def __init__(self, where: Path, size_kib: int) -> None:
        self.where = where
        where.mkdir(parents=True, exist_ok=True)
        self._proc = subprocess.Popen(
            ["unshare", "-rm", sys.executable, __file__, str(where), str(size_kib)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, bufsize=1)
        self._ask("")  # mounted

    def __enter__(self) -> SmallDisk:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def start(self, argv: list[str], log: Path, env: dict[str, str]) -> int:
        """Start ``argv`` inside the namespace with ``env``, its output appended to ``log``
        (best outside the small disk); its pid."""
        return int(self._ask("start " + json.dumps({"argv": argv, "log": str(log),
                                                    "env": env})))

    def run(self, argv: list[str], log: Path, env: dict[str, str]) -> int:
        """Run ``argv`` inside the namespace to its end, as :meth:`start`; its exit status.
        (Only a process inside opens the disk's files: SQLite, for one, resolves
        ``/proc/PID/root`` to ``/``.)"""
        return int(self._ask("run " + json.dumps({"argv": argv, "log": str(log),
                                                  "env": env})))

    def fill(self) -> int:
        """Take every free byte of the disk; how many."""
        return int(self._ask("fill"))

    def free(self) -> None:
        """Give back what :meth:`fill` took."""
        self._ask("free")

    def read_only(self, path: Path) -> None:
        """Make the file ``path`` (on the disk) read-only for whoever opens it from now on."""
        self._ask(f"ro {path}")

    def writable(self, path: Path) -> None:
        """Undo :meth:`read_only` for files opened from now on."""
        self._ask(f"rw {path}")

    def close(self) -> None:
        """Stop what runs inside and unmount the disk."""
        if self._proc.poll() is None:
            assert self._proc.stdin is not None
            self._proc.stdin.close()
            try:
                self._proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()

    def _ask(self, command: str) -> str:
        assert self._proc.stdin is not None and self._proc.stdout is not None
        if command:
            self._proc.stdin.write(command + "\n")
            self._proc.stdin.flush()
        answer = self._proc.stdout.readline().strip()
        if not answer.startswith("ok"):
            raise RuntimeError(f"small disk: {command or 'mount'}: {answer or 'no answer'}")
        return answer[3:]


def _inside(where: Path, size_kib: int) -> None:
    """The script's side: mount, then answer commands until stdin closes."""
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size_kib}k", "tmpfs", str(where)],
                   check=True)
    print("ok", flush=True)
    children: list[subprocess.Popen[bytes]] = []
    for line in sys.stdin:
        verb, _, rest = line.strip().partition(" ")
        try:
            if verb in ("start", "run"):
                spec = json.loads(rest)
                with open(spec["log"], "ab") as log:
                    children.append(subprocess.Popen(spec["argv"], env=spec["env"],
                                                     stdout=log, stderr=log))
                answer = str(children[-1].pid if verb == "start" else children.pop().wait())
            elif verb == "fill":
                answer = str(_fill(where / FILLER))
            elif verb == "free":
                (where / FILLER).unlink(missing_ok=True)
                answer = ""
            elif verb == "ro":
                subprocess.run(["mount", "--bind", rest, rest], check=True)
                subprocess.run(["mount", "-o", "remount,bind,ro", rest], check=True)
                answer = ""
            elif verb == "rw":
                subprocess.run(["umount", "-l", rest], check=True)
                answer = ""
            else:
                raise ValueError(f"unknown command {verb!r}")
        except Exception as exc:  # noqa: BLE001 - answered, for the test to report
            print(f"error {type(exc).__name__}: {exc}", flush=True)
            continue
        print(f"ok {answer}", flush=True)
    for child in children:
        child.terminate()
    for child in children:
        try:
            child.wait(timeout=15)
        except subprocess.TimeoutExpired:
            child.kill()


def _fill(path: Path) -> int:
    taken = 0
    with open(path, "ab", buffering=0) as f:
        for chunk in (65536, 4096, 512, 1):
            while True:
                try:
                    taken += f.write(b"\0" * chunk)
                except OSError as exc:
                    if exc.errno != errno.ENOSPC:
                        raise
                    break
    os.sync()
    return taken


if __name__ == "__main__":
    _inside(Path(sys.argv[1]), int(sys.argv[2]))
