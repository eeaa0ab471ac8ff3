"""Flags shared by the commands that call an LLM, and what they build."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import click

from llm_grop.errors import BadInput
from llm_grop.llm.registry import BACKENDS
from llm_grop.simulation.registry import DEFAULT_SIMULATOR

EPILOG = "Exit status: 0 done, 1 nothing feasible, 2 bad input."

F = TypeVar("F", bound=Callable[..., Any])

_LLM_OPTIONS = [
    click.option("--llm", "backend", default="embedded", show_default=True,
                 help="LLM backend: embedded, openai, replay, or a plugin's "
                      "(see `llm-grop plugins`)."),
    click.option("--model", help="Model name (openai) or GGUF path (embedded)."),
    click.option("--base-url", help="OpenAI-compatible endpoint (default: $OPENAI_BASE_URL)."),
    click.option("--replay", "replay_path", type=click.Path(dir_okay=False, path_type=Path),
                 help="JSONL of recorded calls, for --llm replay."),
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
    click.option("--temperature", default=0.1, show_default=True, type=float),
    click.option("--top-p", default=1.0, show_default=True, type=float),
    click.option("--max-tokens", default=512, show_default=True, type=click.IntRange(1)),
    click.option("--frequency-penalty", default=0.0, show_default=True, type=float),
    click.option("--presence-penalty", default=0.0, show_default=True, type=float),
    click.option("--timeout", "timeout_s", default=60.0, show_default=True, type=float,
                 help="Seconds per LLM request."),
    click.option("--retries", default=3, show_default=True, type=click.IntRange(0),
                 help="Retries on transient LLM errors (connection, 429, 5xx)."),
]


def check_outputs(**paths: Path | None) -> None:
    """:class:`BadInput` for an output path (keyword: its flag, ``_`` for ``-``) that cannot
    be written, before any work is spent."""
    for flag, path in paths.items():
        if path is None:
            continue
        name = "--" + flag.replace("_", "-")
        parent = path.resolve().parent
        if path.is_dir():
            raise BadInput(f"{name} {path}: is a directory; give a file name")
        if not parent.is_dir():
            raise BadInput(f"{name} {path}: directory {parent} does not exist")
        if not os.access(parent, os.W_OK):
            raise BadInput(f"{name} {path}: directory {parent} is not writable")


FEASIBILITY = click.option(
    "--feasibility", default="default", show_default=True,
    help="The planner's feasibility profile: default (assumed) or mujoco (fitted in 3D).")


FIDELITY_WEIGHT = click.option(
    "--fidelity-weight", "fidelity_w", default=1.0, show_default=True,
    type=click.FloatRange(0),
    help="Seconds of GROP's utility that one centimetre of infidelity costs (stated gaps "
         "missed, the setting's shift); 0 ignores fidelity.")


#: ``--table`` of the commands that run in the dining room: the target table's top.
TABLE = click.option(
    "--table", "table_text", metavar="WxD|round:D",
    help="Replace the target table's top: WxD in metres (0.9x0.6) or round:D, a round "
         "top of diameter D (round:1.2) [default: the scene's].")


SIMULATOR = click.option(
    "--simulator", default=DEFAULT_SIMULATOR, show_default=True,
    help="The simulator that executes the plan (see `llm-grop plugins`).")


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
                 **_: Any) -> tuple[Any, Any]:
    """``(BackendOptions, ArrangeOptions)`` from the flags of :func:`llm_flags`."""
    from llm_grop.arrangement.pipeline import ArrangeOptions
    from llm_grop.llm.base import BackendOptions, SamplingParams

    if BACKENDS.key(backend) == "replay" and replay_path is None:
        raise BadInput("--llm replay needs --replay FILE (a JSONL written with --record)")
    params = SamplingParams(temperature, top_p, max_tokens, frequency_penalty, presence_penalty)
    from llm_grop.arrangement.preferences import load_preference_file

    pool = load_preference_file(preferences_file) if preferences_file is not None else ()
    options = ArrangeOptions(m=m, max_attempts=attempts, examples="" if zero_shot else None,
                             notes=notes, params=params, preferences=tuple(prefer),
                             preference_pool=pool)
    llm_options = BackendOptions(model=model, base_url=base_url, timeout_s=timeout_s,
                                 max_retries=retries, replay_path=replay_path)
    return llm_options, options


def check_request(command: str, request: str | None, task: int | None) -> None:
    """:class:`BadInput` unless a non-empty REQUEST or a task was given."""
    if request is None and task is None:
        raise BadInput(f"{command}: give a REQUEST or --task N")
    if request is not None and not request.strip():
        raise BadInput("request: empty; name the objects, e.g. "
                       "'a dinner plate, a dinner fork and a dinner knife'")
