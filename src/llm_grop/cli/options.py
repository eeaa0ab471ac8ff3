"""Flags shared by the commands that call an LLM, and what they build."""

from __future__ import annotations

import logging
import os
import secrets
from collections.abc import Callable
from pathlib import Path
from types import TracebackType
from typing import Any, TypeVar

import click

from llm_grop.errors import BadInput
from llm_grop.llm.registry import BACKENDS
from llm_grop.simulation.mujoco.options import GRASPS
from llm_grop.simulation.registry import DEFAULT_SIMULATOR
from llm_grop.world.table import MAX_TABLE_SIDE_M, MIN_TABLE_SIDE_M, Table

log = logging.getLogger(__name__)

EPILOG = ("Exit status: 0 done, 1 nothing feasible, 2 bad input, 3 LLM service unavailable "
          "(try again later).")

F = TypeVar("F", bound=Callable[..., Any])

#: How to reach a backend: ``llm-grop serve`` takes these too.
_BACKEND_OPTIONS = [
    click.option("--model", help="Model name (openai) or GGUF path (embedded)."),
    click.option("--base-url", help="OpenAI-compatible endpoint (default: $OPENAI_BASE_URL)."),
    click.option("--replay", "replay_path", type=click.Path(dir_okay=False, path_type=Path),
                 help="JSONL of recorded calls, for --llm replay."),
    click.option("--timeout", "timeout_s", default=60.0, show_default=True,
                 type=click.FloatRange(0, min_open=True),
                 help="Seconds one LLM call may take, retries and their waits included."),
    click.option("--max-answer-bytes", default=1024 * 1024, show_default=True,
                 type=click.IntRange(1),
                 help="The largest LLM answer accepted, bytes (openai); a larger one is an "
                      "error."),
    click.option("--retries", default=3, show_default=True, type=click.IntRange(0),
                 help="Retries on transient LLM errors (connection, 429, 5xx)."),
]

_LLM_OPTIONS = [
    click.option("--llm", "backend", default="embedded", show_default=True,
                 help="LLM backend: embedded, openai, replay, or a plugin's "
                      "(see `llm-grop plugins`)."),
    *_BACKEND_OPTIONS,
    _RECORD := click.option("--record", "record_path",
                            type=click.Path(dir_okay=False, path_type=Path),
                            help="Append every LLM call to this JSONL file."),
    click.option("--catalog", "catalog_files", multiple=True,
                 type=click.Path(dir_okay=False, path_type=Path),
                 help="An extra object catalog file (repeatable)."),
    click.option("-m", "--configurations", "m", default=25, show_default=True,
                 type=click.IntRange(1), help="Configurations to sample (M)."),
    click.option("--attempts", default=3, show_default=True, type=click.IntRange(1),
                 help="Template 1 prompts before keeping the largest consistent subset."),
    click.option("--zero-shot", is_flag=True, help="Leave the paper's few-shot examples out."),
    click.option("--notes", default="", help="Text for Template 1's [notes] slot."),
    click.option("--prefer", "prefer", multiple=True, metavar="SENTENCE",
                 help="A relation you want, e.g. 'the dinner fork to the left of the dinner "
                      "plate'; it wins over the LLM (repeatable)."),
    click.option("--preferences", "preferences_file",
                 type=click.Path(dir_okay=False, path_type=Path),
                 help="YAML file `preferences: [sentences]`; those whose objects are all "
                      "requested apply."),
    click.option("--temperature", default=0.1, show_default=True, type=float,
                 help="Sampling temperature of every LLM call (the paper's 0.1)."),
    click.option("--top-p", default=1.0, show_default=True, type=float,
                 help="Nucleus sampling: keep the most likely tokens up to this probability."),
    click.option("--max-tokens", default=512, show_default=True, type=click.IntRange(1),
                 help="Most tokens one LLM answer may have."),
    click.option("--frequency-penalty", default=0.0, show_default=True, type=float,
                 help="Penalty on tokens by how often they appeared (OpenAI's meaning)."),
    click.option("--presence-penalty", default=0.0, show_default=True, type=float,
                 help="Penalty on tokens that appeared at all (OpenAI's meaning)."),
]


#: The suffix each picture or video flag's file must have (the format its writer makes),
#: and what to say when it has another.
OUTPUT_SUFFIXES: dict[str, tuple[str, str]] = {
    "image": (".png", "only PNG pictures are made; use a name ending in .png"),
    "table_image": (".png", "only PNG pictures are made; use a name ending in .png"),
    "room_image": (".png", "only PNG pictures are made; use a name ending in .png"),
    "video": (".mp4", "the video must be an .mp4 file"),
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
        self._staged: dict[Path, tuple[str, Path]] = {}

    def __enter__(self) -> StagedOutputs:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.discard()

    def path(self, flag: str, final: Path) -> Path:
        """A fresh temporary path beside ``final``, moved to ``final`` at the commit."""
        # Short whatever the output's name, and with its suffix (a format check reads it).
        suffix = final.suffix if len(final.suffix) <= _SUFFIX_CHARS else ""
        tmp = final.with_name(f".{final.stem[:_STEM_CHARS]}.{os.getpid()}-"
                              f"{secrets.token_hex(4)}.part{suffix}")
        self._staged[final] = (flag, tmp)
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
        for final, (flag, tmp) in list(self._staged.items()):
            if not tmp.exists():
                continue
            try:
                os.replace(tmp, final)
            except OSError as exc:
                raise BadInput(f"{_flag(flag)} {final}: cannot write ({exc.strerror})") \
                    from None
            del self._staged[final]

    def discard(self) -> None:
        """Remove the temporary files not yet committed (never a user's own file)."""
        for _, tmp in self._staged.values():
            tmp.unlink(missing_ok=True)
        self._staged.clear()


FEASIBILITY = click.option(
    "--feasibility", default="default", show_default=True,
    help="The planner's feasibility profile: default (assumed) or mujoco (fitted in 3D).")


WEIGHT = click.option(
    "--weight", "w", default=40.0, show_default=True, type=click.FloatRange(0),
    help="GROP's utility weight w (seconds per unit of success probability).")

FIDELITY_WEIGHT = click.option(
    "--fidelity-weight", "fidelity_w", default=1.0, show_default=True,
    type=click.FloatRange(0),
    help="Seconds of GROP's utility that one centimetre of infidelity costs (stated gaps "
         "missed, the setting's shift); 0 ignores fidelity.")


def _parse_table(ctx: click.Context, param: click.Parameter, text: str | None) -> Table | None:
    """``--table``'s text as a :class:`Table` (checked as the flags are read)."""
    return None if text is None else Table.parse(text)


#: ``--table`` of ``arrange``, ``run`` and ``bench``: the target table's top, a
#: :class:`~llm_grop.world.table.Table` (``None``: the command's default).
TABLE = click.option(
    "--table", "table", metavar="WxD|round:D", callback=_parse_table,
    help=f"The target table's top: WxD such as 120x80cm, 1.2x0.8m or 1200x800mm (a bare "
         f"number is metres: 0.9x0.6), or round:D, a round top of diameter D such as "
         f"round:120cm; each side {MIN_TABLE_SIDE_M:g} to {MAX_TABLE_SIDE_M:g} m "
         f"[default: arrange 0.9x0.6 m; run and bench the scene's].")


SIMULATOR = click.option(
    "--simulator", default=DEFAULT_SIMULATOR, show_default=True,
    help="The simulator that executes the plan (see `llm-grop plugins`).")

TRUTH = click.option(
    "--truth", metavar="PROFILE",
    help="--simulator kinematic2d: draw outcomes and durations from this feasibility "
         "profile (mujoco: what the 3D world was measured to do) [default: the 2D "
         "simulator's own, the default profile's curves].")

GRASP = click.option(
    "--grasp", default="fix", show_default=True, type=click.Choice(GRASPS),
    help="--simulator mujoco: how the hand holds. fix: a weld that attaches only when both "
         "pads squeeze the object (Gazebo's grasp-fix); friction: contact friction alone "
         "(the README lists what it can carry).")


def attempt_flags(f: F) -> F:
    """Add the executive's attempt counts, ``--nav-attempts`` and ``--manip-attempts``."""
    f = click.option(
        "--manip-attempts", "manip_attempts", type=click.IntRange(1),
        help="Attempts per pick and per place of each object, re-grasps included "
             "[default: the method's: 20 for llm-grop, 10 for the others, as the authors "
             "ran them].")(f)
    return click.option(
        "--nav-attempts", "nav_attempts", default=3, show_default=True,
        type=click.IntRange(1),
        help="Attempts per navigation goal before the next fallback standing position.")(f)


NO_GUESS = click.option(
    "--no-guess", "no_guess", is_flag=True,
    help="Refuse a request the LLM would have to complete: objects it does not name "
         "(a meal, 'coffee'), or how many.")


def backend_flags(f: F) -> F:
    """Add the flags that say how to reach a backend (``--model``, ``--base-url``, ...)."""
    for option in reversed(_BACKEND_OPTIONS):
        f = option(f)
    return f


def backend_options(model: str | None, base_url: str | None, replay_path: Path | None,
                    timeout_s: float, retries: int, max_answer_bytes: int, **_: Any) -> Any:
    """The :class:`~llm_grop.llm.base.BackendOptions` of :func:`backend_flags`' flags."""
    from llm_grop.llm.base import BackendOptions

    return BackendOptions(model=model, base_url=base_url, timeout_s=timeout_s,
                          max_retries=retries, replay_path=replay_path,
                          max_answer_bytes=max_answer_bytes)


def llm_flags(f: F) -> F:
    """Add the LLM and arrangement flags to a command."""
    for option in reversed(_LLM_OPTIONS):
        f = option(f)
    return f


def llm_flags_without_record(f: F) -> F:
    """The LLM and arrangement flags but ``--record`` (for commands that run in parallel)."""
    for option in reversed(_LLM_OPTIONS):
        if option is not _RECORD:
            f = option(f)
    return f


def llm_settings(backend: str, model: str | None, base_url: str | None,
                 replay_path: Path | None, m: int, attempts: int, zero_shot: bool, notes: str,
                 temperature: float, top_p: float, max_tokens: int, frequency_penalty: float,
                 presence_penalty: float, timeout_s: float, retries: int,
                 prefer: tuple[str, ...] = (), preferences_file: Path | None = None,
                 max_answer_bytes: int = 1024 * 1024, **_: Any) -> tuple[Any, Any]:
    """``(BackendOptions, ArrangeOptions)`` from the flags of :func:`llm_flags`."""
    from llm_grop.arrangement.pipeline import ArrangeOptions
    from llm_grop.llm.base import SamplingParams

    if BACKENDS.key(backend) == "replay" and replay_path is None:
        raise BadInput("--llm replay needs --replay FILE (a JSONL written with --record)")
    params = SamplingParams(temperature, top_p, max_tokens, frequency_penalty, presence_penalty)
    from llm_grop.arrangement.preferences import load_preference_file

    pool = load_preference_file(preferences_file) if preferences_file is not None else ()
    options = ArrangeOptions(m=m, max_attempts=attempts, examples="" if zero_shot else None,
                             notes=notes, params=params, preferences=tuple(prefer),
                             preference_pool=pool)
    llm_options = backend_options(model, base_url, replay_path, timeout_s, retries,
                                  max_answer_bytes)
    return llm_options, options


def check_request(command: str, request: str | None, task: int | None) -> None:
    """:class:`BadInput` unless a non-empty REQUEST or a task was given."""
    if request is None and task is None:
        raise BadInput(f"{command}: give a REQUEST or --task N")
    if request is not None and not request.strip():
        raise BadInput("request: empty; name the objects, e.g. "
                       "'a dinner plate, a dinner fork and a dinner knife'")

