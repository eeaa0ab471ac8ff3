"""How llm-grop writes JSON: numbers rounded to 0.1 mm, UTF-8 text, atomic files."""

from __future__ import annotations

import json
import os
import stat
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from llm_grop.errors import BadInput

#: Decimal places kept for metres and radians in JSON (0.1 mm).
_DIGITS = 4
#: How much of a file's name its temporary file's name keeps (characters), so that it
#: stays within a file system's 255 bytes.
_TMP_NAME_CHARS = 48


def rounded(value: float) -> float:
    """``value`` rounded to 0.1 mm / 0.1 mrad for JSON, without negative zero."""
    return round(float(value), _DIGITS) + 0.0  # + 0.0 turns -0.0 into 0.0


def dumps(data: Mapping[str, Any]) -> str:
    """JSON text as llm-grop writes it: UTF-8, two-space indent, trailing newline."""
    return json.dumps(data, indent=2, ensure_ascii=False) + "\n"


def write_json(path: str | Path, data: Mapping[str, Any]) -> None:
    """Write ``data`` to ``path`` atomically: to a new temporary file beside it, then
    renamed over it, so a failure never leaves half a file nor loses the one there.

    The file gets the mode of the file it replaces, else the usual one (``0o666`` less
    the umask). Raises :class:`BadInput` (one line, naming ``path``) if it cannot be
    written.
    """
    # A value JSON cannot hold fails here, before any file is touched.
    write_text(path, dumps(data))


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically, as :func:`write_json` does."""
    write_bytes(path, text.encode("utf-8"))


def output_target(path: Path) -> tuple[Path, bool]:
    """Where a file written to ``path`` lands, and whether it is streamed into it rather
    than renamed over it: a symbolic link is written through (its target is replaced, the
    link kept), and an existing file that is not a regular one (a terminal, a pipe,
    ``/dev/stdout``) is written into as it is, never replaced."""
    try:
        mode = path.stat().st_mode  # through a link
    except OSError:
        return Path(os.path.realpath(path)), False  # a link to nothing yet: its target
    if not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
        return path, True
    return Path(os.path.realpath(path)), False


def write_bytes(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically, as :func:`write_json` does: a temporary file
    of its own beside it (so concurrent writers of one path never meet), synced, then
    renamed over it (through a link, and straight into a pipe or a terminal:
    :func:`output_target`)."""
    path = Path(path)
    target, streamed = output_target(path)
    if streamed:
        try:
            with open(path, "wb") as f:
                f.write(data)
        except OSError as exc:
            raise BadInput(f"{path}: cannot write ({exc.strerror or exc})") from None
        return
    try:
        fd, name = tempfile.mkstemp(prefix=f".{target.name[:_TMP_NAME_CHARS]}.",
                                    suffix=".tmp", dir=target.parent)
    except OSError as exc:
        raise BadInput(f"{path}: cannot write ({exc.strerror or exc})") from None
    tmp = Path(name)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, _mode_for(target))
        os.replace(tmp, target)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise BadInput(f"{path}: cannot write ({exc.strerror or exc})") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _mode_for(path: Path) -> int:
    """The permission bits a file written to ``path`` gets: those of the file it replaces,
    else ``0o666`` less the process's umask."""
    try:
        return stat.S_IMODE(path.stat().st_mode)
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask
