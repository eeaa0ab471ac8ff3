"""What the commands share besides the settings record's flags (:mod:`.settings`): the
exit statuses, output paths checked before any work, and outputs written all or none."""

from __future__ import annotations

import logging
import os
import secrets
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path
from types import TracebackType
from typing import Any, TypeVar

import click

from llm_grop.errors import BadInput
from llm_grop.files.jsonio import output_target

log = logging.getLogger(__name__)

EPILOG = ("Exit status: 0 done, 1 nothing feasible, 2 bad input, 3 LLM service unavailable "
          "(try again later).")

F = TypeVar("F", bound=Callable[..., Any])

#: ``--record`` of the commands that call an LLM in one process (not bench or sweep).
RECORD = click.option("--record", "record_path", type=click.Path(dir_okay=False, path_type=Path),
                      help="Append every LLM call to this JSONL file.")

#: ``-q``: print nothing but errors.
QUIET = click.option("-q", "--quiet", is_flag=True, help="Print nothing but errors.")


#: The suffix each picture or video flag's file must have (the format its writer makes),
#: and what to say when it has another.
OUTPUT_SUFFIXES: dict[str, tuple[str, str]] = {
    "image": (".png", "only PNG pictures are made; use a name ending in .png"),
    "table_image": (".png", "only PNG pictures are made; use a name ending in .png"),
    "room_image": (".png", "only PNG pictures are made; use a name ending in .png"),
    "video": (".mp4", "the video must be an .mp4 file"),
    "rerun": (".rrd", "a Rerun recording's name ends in .rrd"),
    "mcap": (".mcap", "a ROS 2 bag's name ends in .mcap"),
}


def _flag(keyword: str) -> str:
    """The flag a keyword stands for: ``table_image`` -> ``--table-image``."""
    return "--" + keyword.replace("_", "-")


def check_outputs(**paths: Path | None) -> None:
    """:class:`BadInput` for an output path (keyword: its flag, ``_`` for ``-``) that cannot
    be written, before any work is spent: a directory, a file that is not writable, a
    directory that does not exist or is not writable, or a picture or video whose name
    does not end in its format's suffix (:data:`OUTPUT_SUFFIXES`)."""
    for flag, path in paths.items():
        if path is not None:
            _checked(_check_output, flag, path)


def _checked(check: Callable[[str, Path], None], flag: str, path: Path) -> None:
    """``check(flag, path)``, an operating system's complaint about the path (a name too
    long, a loop of links) made a :class:`BadInput` naming the flag."""
    try:
        check(flag, path)
    except (OSError, RuntimeError) as exc:
        words = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise BadInput(f"{_flag(flag)} {path}: {words}") from None


def _check_output(flag: str, path: Path) -> None:
    """:func:`check_outputs` for one ``path``, given with the flag keyword ``flag``."""
    name = _flag(flag)
    parent = path.resolve().parent
    if path.is_dir():
        raise BadInput(f"{name} {path}: is a directory; give a file name")
    if flag in OUTPUT_SUFFIXES:
        suffix, words = OUTPUT_SUFFIXES[flag]
        if path.suffix.lower() != suffix:
            raise BadInput(f"{name} {path}: {words}")
    if output_target(path)[1]:  # a pipe or a terminal: written into, its directory untouched
        if not os.access(path, os.W_OK):
            raise BadInput(f"{name} {path}: the file is not writable")
        return
    if not parent.is_dir():
        raise BadInput(f"{name} {path}: directory {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise BadInput(f"{name} {path}: directory {parent} is not writable")
    if path.exists() and not os.access(path, os.W_OK):
        raise BadInput(f"{name} {path}: the file is not writable")


def check_out_dir(flag: str, path: Path) -> None:
    """:class:`BadInput` unless ``path`` is, or can be made, a writable directory (``flag``
    names it in the message): checked before any work is spent."""
    _checked(_check_dir, flag, path)


def _check_dir(flag: str, path: Path) -> None:
    """:func:`check_out_dir` for ``path``, given with the flag keyword ``flag``."""
    name = _flag(flag)
    if path.exists():
        if not path.is_dir():
            raise BadInput(f"{name} {path}: is a file; give a directory")
        if not os.access(path, os.W_OK | os.X_OK):
            raise BadInput(f"{name} {path}: directory is not writable")
        return
    ancestor = path.resolve().parent
    while not ancestor.exists():
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise BadInput(f"{name} {path}: {ancestor} is a file, so the directory cannot be made")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise BadInput(f"{name} {path}: cannot be made, {ancestor} is not writable")


#: How much of an output's name and suffix its temporary file's name keeps (characters),
#: so that it stays within a file system's 255 bytes.
_STEM_CHARS = 48
_SUFFIX_CHARS = 16


class StagedOutputs:
    """The files a command writes after its work, written all or none.

    :meth:`path` gives a temporary name beside each output (hidden, with the output's
    suffix, so the writer's format check still holds); :meth:`write` writes one there,
    and a failure is reported naming the output's flag and path. :meth:`commit` moves
    every written file into place; leaving the ``with`` block without a commit removes
    the temporary files. A user's existing file is replaced only at the commit, so a
    failure never loses it, and never leaves half a set of outputs.
    """

    def __init__(self) -> None:
        # Per output: its flag, the temporary file, where it lands and whether it is
        # streamed there (:func:`~llm_grop.files.jsonio.output_target`).
        self._staged: dict[Path, tuple[str, Path, Path, bool]] = {}

    def __enter__(self) -> StagedOutputs:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.discard()

    def path(self, flag: str, final: Path) -> Path:
        """A fresh temporary path beside ``final``, moved to ``final`` at the commit."""
        target, streamed = output_target(final)
        # Short whatever the output's name, and with its suffix (a format check reads it).
        suffix = final.suffix if len(final.suffix) <= _SUFFIX_CHARS else ""
        name = f".{final.stem[:_STEM_CHARS]}.{os.getpid()}-{secrets.token_hex(4)}.part{suffix}"
        # A pipe or a terminal is written into at the commit, from a file staged apart.
        tmp = Path(tempfile.gettempdir()) / name if streamed else target.with_name(name)
        self._staged[final] = (flag, tmp, target, streamed)
        return tmp

    def write(self, flag: str, final: Path | None, writer: Callable[[Path], object]) -> None:
        """``writer(tmp)`` for the output ``final`` (nothing when ``None``); its failure is
        a :class:`BadInput` that names ``flag`` and ``final``, not the temporary file."""
        if final is None:
            return
        tmp = self.path(flag, final)
        try:
            writer(tmp)
        except OSError as exc:
            raise BadInput(f"{_flag(flag)} {final}: cannot write ({exc.strerror or exc})") \
                from None
        except BadInput as exc:
            raise BadInput(f"{_flag(flag)}: {str(exc).replace(str(tmp), str(final))}") \
                from None

    def commit(self) -> None:
        """Move every written file into place."""
        for final, (flag, tmp, target, streamed) in list(self._staged.items()):
            if not tmp.exists():
                continue
            try:
                if streamed:
                    with tmp.open("rb") as src, open(final, "wb") as out:
                        shutil.copyfileobj(src, out)
                    tmp.unlink()
                else:
                    os.replace(tmp, target)
            except OSError as exc:
                raise BadInput(f"{_flag(flag)} {final}: cannot write ({exc.strerror})") \
                    from None
            del self._staged[final]

    def discard(self) -> None:
        """Remove the temporary files not yet committed (never a user's own file)."""
        for _, tmp, _, _ in self._staged.values():
            tmp.unlink(missing_ok=True)
        self._staged.clear()


def check_request(command: str, request: str | None, task: int | None) -> None:
    """:class:`BadInput` unless a non-empty REQUEST or a task was given."""
    if request is None and task is None:
        raise BadInput(f"{command}: give a REQUEST or --task N")
    if request is not None and not request.strip():
        raise BadInput("request: empty; name the objects, e.g. "
                       "'a dinner plate, a dinner fork and a dinner knife'")

