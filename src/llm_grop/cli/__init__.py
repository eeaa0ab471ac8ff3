"""The ``llm-grop`` command: parses flags, calls the API, maps errors to exit codes."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable

import click

from llm_grop.cli.arrange import arrange
from llm_grop.cli.bench import bench
from llm_grop.cli.doctor import doctor
from llm_grop.cli.flags import reworded
from llm_grop.cli.learn import learn
from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG
from llm_grop.cli.plugins import plugins
from llm_grop.cli.rate import rate
from llm_grop.cli.ratings import ratings
from llm_grop.cli.run import run
from llm_grop.cli.schema import schema
from llm_grop.cli.serve import serve
from llm_grop.cli.sweep import sweep
from llm_grop.cli.view import view
from llm_grop.errors import INTERNAL_ERROR_EXIT, LLMGropError, interrupted


@click.group(epilog=EPILOG, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="llm-grop")
@VERBOSE
def cli() -> None:
    """llm-grop: set a table the way people expect (LLM-GROP, IROS 2023)."""


cli.add_command(arrange)
cli.add_command(run)
cli.add_command(bench)
cli.add_command(sweep)
cli.add_command(rate)
cli.add_command(learn)
cli.add_command(ratings)
cli.add_command(schema)
cli.add_command(plugins)
cli.add_command(serve)
cli.add_command(doctor)
cli.add_command(view)


def main(argv: list[str] | None = None, signalled: Callable[[], bool] | None = None) -> int:
    """Entry point: runs the command, printing one line and no traceback on failure.

    ``signalled`` says whether an interrupt (Ctrl-C, SIGTERM) has arrived: the console
    script's handler (:mod:`llm_grop.entry`) knows. A failure after one is reported as the
    interrupt, because an interrupt raised inside an extension (shapely's, numpy's) can
    surface as an error of its own with no ``KeyboardInterrupt`` in its chain.
    """
    try:
        code = cli.main(args=argv, prog_name="llm-grop", standalone_mode=False)
    except click.exceptions.Abort:
        click.echo("llm-grop: interrupted", err=True)
        return 130
    except click.exceptions.NoArgsIsHelpError as exc:
        click.echo(exc.format_message())
        return 0
    except Exception as exc:  # noqa: BLE001 - the contract promises no traceback
        if interrupted(exc) or (signalled is not None and signalled()):
            click.echo("llm-grop: interrupted", err=True)
            return 130
        return _failed(exc)
    return code if isinstance(code, int) else 0


def _failed(exc: Exception) -> int:
    """Print the one line for the failure ``exc``; its exit status."""
    if isinstance(exc, click.ClickException):
        ctx = getattr(exc, "ctx", None)
        where = f"{ctx.command_path}: " if ctx is not None else ""
        click.echo(f"llm-grop: error: {where}{exc.format_message()}", err=True)
        return 2
    if isinstance(exc, LLMGropError):
        click.echo(f"llm-grop: error: {reworded(exc)}", err=True)
        return exc.exit_code
    if isinstance(exc, OSError):
        click.echo(f"llm-grop: error: {exc.filename or ''}: {exc.strerror or exc}", err=True)
        return 2
    if os.environ.get("LLM_GROP_DEBUG"):
        raise exc
    click.echo(f"llm-grop: internal error: {type(exc).__name__}: {exc} "
               "(set LLM_GROP_DEBUG=1 for a traceback)", err=True)
    return INTERNAL_ERROR_EXIT

if __name__ == "__main__":
    sys.exit(main())
