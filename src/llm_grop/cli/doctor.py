"""``llm-grop doctor``: checks, without network, that every part llm-grop needs is there."""

from __future__ import annotations

import json
import os
from dataclasses import asdict

import click

from llm_grop.cli.logs import VERBOSE

#: The doctor's exit statuses (1 here is not "nothing feasible", as elsewhere).
DOCTOR_EPILOG = ("Exit status: 0 every needed part is there (a warning is an optional part "
                 "missing), 1 a needed part is missing, 2 bad input.")

#: Colour of each status's mark on a terminal.
_COLOURS = {"ok": "green", "warn": "yellow", "fail": "red", "skip": None}


@click.command(epilog=DOCTOR_EPILOG)
@click.option("--base-url", help="An OpenAI-compatible server to check: reachable, and "
              "the model listed by GET /models (default: $OPENAI_BASE_URL; none: skipped).")
@click.option("--model", help="The model the server must list (default: the openai "
              "backend's default model).")
@click.option("--json", "as_json", is_flag=True,
              help="Print a JSON list of the checks (name, status, detail, fix) instead.")
@VERBOSE
def doctor(base_url: str | None, model: str | None, as_json: bool) -> int:
    """Check that every part llm-grop needs is there, each with the command that fixes it.

    One line per check: the Python version, a portable llama.cpp build (not a native
    AVX-512/AMX one), offscreen OpenGL for MuJoCo (a frame rendered in a child process),
    the embedded model's file, Chromium for the browser tests, the optional extras
    (ratings, ray, serve) and a configured OpenAI-compatible server. It uses no network,
    except to ask that server for its models. Marks: ok, warn (an optional part is
    missing), FAIL (a needed part is missing), skip.
    """
    from llm_grop.doctor import checks, healthy, report_line

    configured = base_url or os.environ.get("OPENAI_BASE_URL") or None
    found = []
    for check in checks(configured, model, os.environ.get("OPENAI_API_KEY")):
        result = check()
        found.append(result)
        if not as_json:
            line = report_line(result)
            mark, rest = line[:4], line[4:]
            click.echo(click.style(mark, fg=_COLOURS[result.status.value], bold=True) + rest)
    if as_json:
        click.echo(json.dumps([{**asdict(c), "status": c.status.value} for c in found],
                              indent=2))
    return 0 if healthy(found) else 1
