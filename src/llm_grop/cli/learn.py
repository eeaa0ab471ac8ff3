"""``llm-grop learn``: a person's way of setting the table, learned from example settings
as preference sentences (issue 42; :mod:`llm_grop.arrangement.learning`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from llm_grop.cli.execution import NO_CACHE, cache_setting
from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG, QUIET, StagedOutputs, check_outputs
from llm_grop.cli.settings import LLM_FIELDS, checked_settings, flags
from llm_grop.errors import BadInput


@click.command(epilog=EPILOG)
@VERBOSE
@click.argument("examples", metavar="EXAMPLE...", nargs=-1, required=True,
                type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", "out_path", required=True,
              type=click.Path(dir_okay=False, path_type=Path),
              help="Write the learned preferences file (YAML `preferences: [sentences]`, "
                   "for --preferences) here.")
@click.option("--force", is_flag=True,
              help="Replace the --out file if it exists (a preferences file may be "
                   "written by hand, so it is never replaced unasked).")
@click.option("--exact", is_flag=True,
              help="Learn only what the examples show: ask no LLM for rules about the "
                   "catalog's other objects.")
@flags("catalog_files", *LLM_FIELDS, "seed", "cache", help={"seed": "Seed of the LLM's call."})
@NO_CACHE
@QUIET
def learn(examples: tuple[Path, ...], out_path: Path, force: bool,
          exact: bool, quiet: bool, no_cache: bool,
          **params: Any) -> None:
    """Learn how a person sets the table from EXAMPLE settings, as preference sentences.

    Each EXAMPLE is a table setting: an arrangement JSON (`llm-grop arrange --json`, or
    any system's in the same shape) or a run JSON (its `final`). What holds in every
    example that shows both objects becomes a sentence with the median gap ("the dinner
    fork 2 cm to the right of the dinner plate"); what the examples disagree on is
    reported, not learned. Then the LLM is asked where the same person would put the
    catalog's other objects; its rules are checked by clingo against what the examples
    show, which always wins (`--exact`: no LLM). Use the file with `--preferences`.
    """
    from rich.console import Console
    from rich.table import Table as RichTable
    from rich.text import Text

    from llm_grop.api import learn as learn_examples
    from llm_grop.cli.console import print_warnings
    from llm_grop.files.jsonio import output_target, write_text

    # The output is checked before any example is read.
    check_outputs(out=out_path)
    if out_path.exists() and not force and not output_target(out_path)[1]:
        raise BadInput(f"--out {out_path}: already exists; give --force to replace it")
    if out_path.resolve() in {e.resolve() for e in examples}:
        raise BadInput(f"--out {out_path}: is one of the examples")
    settings = checked_settings(params, cache=cache_setting(params["cache"], no_cache))
    learned = learn_examples(examples, settings, generalise=not exact)
    with StagedOutputs() as outputs:
        outputs.write("out", out_path, lambda p: write_text(p, learned.preference_file()))
        outputs.commit()
    if quiet:
        return
    # What was not learned is also said in the file's header.
    print_warnings([*learned.warnings, *(c.message() for c in learned.contradictions)],
                   Console(stderr=True))
    out = Console()
    table = RichTable(title=f"Learned from {len(learned.examples)} example"
                            f"{'' if len(learned.examples) == 1 else 's'}",
                      title_justify="left")
    table.add_column("preference")
    table.add_column("seen (cm)", justify="right")
    table.add_column("settings", justify="right")
    for s in learned.sentences:
        seen = "" if s.spread_cm is None else \
            f"{s.spread_cm[0]:g}" if s.spread_cm[0] == s.spread_cm[1] else \
            f"{s.spread_cm[0]:g} to {s.spread_cm[1]:g}"
        # Object names come from the examples: never rich markup.
        table.add_row(Text(s.sentence), seen, str(len(s.sources)))
    out.print(table)
    out.print(Text(f"Wrote preferences: {out_path}"), soft_wrap=True)
