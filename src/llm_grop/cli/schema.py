"""``llm-grop schema``: the JSON Schema of one of the contract's documents."""

from __future__ import annotations

import click

from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG
from llm_grop.contract.schemas import DOCUMENTS, schema_text


@click.command(epilog=EPILOG)
@VERBOSE
@click.argument("name", type=click.Choice(sorted(DOCUMENTS)))
def schema(name: str) -> None:
    """Print the JSON Schema of the arrangement JSON, the run JSON, a bench trial row or the
    plan JSON (`llm-grop serve`).

    The same files are in docs/schema/ of the source tree; validate a file with any JSON
    Schema tool, e.g. `check-jsonschema --schemafile run.schema.json run.json`.
    """
    click.echo(schema_text(name), nl=False)
