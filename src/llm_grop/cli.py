"""The ``llm-grop`` command: parses flags, calls the API, maps errors to exit codes."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click

from llm_grop.errors import BadInput, LLMGropError

_EPILOG = "Exit status: 0 done, 1 nothing feasible, 2 bad input."


@click.group(epilog=_EPILOG)
@click.version_option(package_name="llm-grop")
def cli() -> None:
    """llm-grop: set a table the way people expect (LLM-GROP, IROS 2023)."""


@cli.command(epilog=_EPILOG)
@click.argument("request", required=False)
@click.option("--task", type=click.IntRange(1),
              help="Use the objects of the paper's Table I task N.")
@click.option("--table", "table_size", default="0.9x0.6", show_default=True,
              help="Table top WxD in metres.")
@click.option("--seed", default=0, show_default=True,
              help="Seed for every LLM call and the sampler.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Write the arrangement JSON here.")
@click.option("--image", "image_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Write a top-down PNG of the table here.")
@click.option("--llm", "backend", default="embedded", show_default=True,
              help="LLM backend: embedded, openai or replay.")
@click.option("--model", help="Model name (openai) or GGUF path (embedded).")
@click.option("--base-url", help="OpenAI-compatible endpoint (default: $OPENAI_BASE_URL).")
@click.option("--replay", "replay_path", type=click.Path(dir_okay=False, path_type=Path),
              help="JSONL of recorded calls, for --llm replay.")
@click.option("--record", "record_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Append every LLM call to this JSONL file.")
@click.option("--catalog", "catalog_files", multiple=True,
              type=click.Path(dir_okay=False, path_type=Path),
              help="An extra object catalog file (repeatable).")
@click.option("-m", "--configurations", "m", default=25, show_default=True,
              type=click.IntRange(1), help="Configurations to sample (M).")
@click.option("--attempts", default=3, show_default=True, type=click.IntRange(1),
              help="Template 1 prompts before keeping the largest consistent subset.")
@click.option("--zero-shot", is_flag=True, help="Leave the paper's few-shot examples out.")
@click.option("--notes", default="", help="Text for Template 1's [notes] slot.")
@click.option("--temperature", default=0.1, show_default=True, type=float)
@click.option("--top-p", default=1.0, show_default=True, type=float)
@click.option("--max-tokens", default=512, show_default=True, type=click.IntRange(1))
@click.option("--frequency-penalty", default=0.0, show_default=True, type=float)
@click.option("--presence-penalty", default=0.0, show_default=True, type=float)
@click.option("--timeout", "timeout_s", default=60.0, show_default=True, type=float,
              help="Seconds per LLM request.")
@click.option("--retries", default=3, show_default=True, type=click.IntRange(0),
              help="Retries on transient LLM errors (connection, 429, 5xx).")
@click.option("-q", "--quiet", is_flag=True, help="Print nothing but errors.")
def arrange(request: str | None, task: int | None, table_size: str, seed: int,
            json_path: Path | None, image_path: Path | None, backend: str, model: str | None,
            base_url: str | None, replay_path: Path | None, record_path: Path | None,
            catalog_files: tuple[Path, ...], m: int, attempts: int, zero_shot: bool, notes: str,
            temperature: float, top_p: float, max_tokens: int, frequency_penalty: float,
            presence_penalty: float, timeout_s: float, retries: int, quiet: bool) -> None:
    """Arrange the objects of REQUEST on the table (paper §III-A, §III-B)."""
    from rich.console import Console

    from llm_grop.api import arrange as api_arrange
    from llm_grop.arrangement.pipeline import ArrangeOptions
    from llm_grop.llm.base import BackendOptions, SamplingParams
    from llm_grop.world.serialize import arrangement_to_dict, write_json
    from llm_grop.world.table import Table

    if request is None and task is None:
        raise BadInput("arrange: give a REQUEST or --task N")
    if request is not None and not request.strip():
        raise BadInput("request: empty; name the objects, e.g. "
                       "'a dinner plate, a dinner fork and a dinner knife'")
    if backend == "replay" and replay_path is None:
        raise BadInput("--llm replay needs --replay FILE (a JSONL written with --record)")
    table = Table.parse(table_size)
    params = SamplingParams(temperature, top_p, max_tokens, frequency_penalty, presence_penalty)
    options = ArrangeOptions(m=m, max_attempts=attempts, examples="" if zero_shot else None,
                             notes=notes, params=params)
    llm_options = BackendOptions(model=model, base_url=base_url, timeout_s=timeout_s,
                                 max_retries=retries, replay_path=replay_path)
    out = Console()
    err = Console(stderr=True)
    with err.status("starting", spinner="dots") as status:
        def on_event(message: str) -> None:
            if not quiet:
                status.update(message)

        result = api_arrange(request, task=task, llm=backend, llm_options=llm_options,
                             table=table, seed=seed, catalog_files=catalog_files,
                             options=options, record=record_path, on_event=on_event)
    if json_path is not None:
        write_json(json_path, arrangement_to_dict(result.arrangement))
    if image_path is not None:
        from llm_grop.render.table import draw_arrangement

        draw_arrangement(result.arrangement, image_path)
    if not quiet:
        from llm_grop.render.console import print_arrangement

        print_arrangement(result, out)
        for label, path in (("arrangement JSON", json_path), ("picture", image_path)):
            if path is not None:
                out.print(f"Wrote {label}: {path}")


def main(argv: list[str] | None = None) -> int:
    """Entry point: runs the command, printing one line and no traceback on failure."""
    try:
        cli.main(args=argv, prog_name="llm-grop", standalone_mode=False)
    except click.exceptions.Abort:
        click.echo("llm-grop: interrupted", err=True)
        return 130
    except click.exceptions.NoArgsIsHelpError as exc:
        click.echo(exc.format_message())
        return 0
    except click.ClickException as exc:
        ctx = getattr(exc, "ctx", None)
        where = f"{ctx.command_path}: " if ctx is not None else ""
        click.echo(f"llm-grop: error: {where}{exc.format_message()}", err=True)
        return 2
    except LLMGropError as exc:
        click.echo(f"llm-grop: error: {exc}", err=True)
        return exc.exit_code
    except OSError as exc:
        click.echo(f"llm-grop: error: {exc.filename or ''}: {exc.strerror or exc}", err=True)
        return 2
    except Exception as exc:  # noqa: BLE001 - the contract promises no traceback
        if os.environ.get("LLM_GROP_DEBUG"):
            raise
        click.echo(f"llm-grop: internal error: {type(exc).__name__}: {exc} "
                   "(set LLM_GROP_DEBUG=1 for a traceback)", err=True)
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
