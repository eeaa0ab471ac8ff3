"""``llm-grop plugins``: every LLM backend, method, simulator and executor, and where it
comes from."""

from __future__ import annotations

import click

from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG
from llm_grop.errors import BadInput


@click.command(epilog=EPILOG)
@VERBOSE
def plugins() -> None:
    """List the LLM backends, methods, simulators and executors available, shipped or from
    plugins.

    A package adds its own through the entry point groups llm_grop.llm_backends,
    llm_grop.methods, llm_grop.simulators and llm_grop.executors (see the README's
    "Plugins").
    """
    from rich.console import Console
    from rich.table import Table as RichTable

    from llm_grop.experiment.executors import EXECUTORS
    from llm_grop.llm.registry import BACKENDS, backend_options_class
    from llm_grop.methods.registry import METHODS
    from llm_grop.settings.declared import option_defaults
    from llm_grop.simulation.registry import SIMULATORS, simulator_class

    table = RichTable(title="Available components", title_justify="left")
    for column in ("kind", "name", "chosen with", "from"):
        table.add_column(column)
    for registry in (BACKENDS, METHODS, SIMULATORS, EXECUTORS):
        for name in registry.names():
            table.add_row(registry.kind, name, f"{registry.flag} {name}",
                          registry.origin(name))
    console = Console()
    console.print(table)
    own = RichTable(title="Options each LLM backend and method declares (--llm-option and "
                          "--method-option KEY=VALUE set one; the defaults shown)",
                    title_justify="left")
    for column in ("kind", "name", "options"):
        own.add_column(column)
    for registry, declared in ((BACKENDS, backend_options_class),
                               (METHODS, lambda n: METHODS.get(n).Options)):
        for name in registry.names():
            try:
                own.add_row(registry.kind, name, option_defaults(declared(name)))
            except BadInput as exc:
                own.add_row(registry.kind, name, f"cannot load: {exc}")
    console.print(own)
    sims = RichTable(title="What each simulator declares (--sim-option KEY=VALUE sets an "
                           "option; the defaults shown)", title_justify="left")
    for column in ("simulator", "options", "pictures", "video", "cameras"):
        sims.add_column(column)
    for name in SIMULATORS.names():
        try:
            cls = simulator_class(name)
        except BadInput as exc:
            sims.add_row(name, f"cannot load: {exc}", "", "", "")
            continue
        sims.add_row(name, option_defaults(cls.Options), _yes(cls.supports_pictures),
                     _yes(cls.supports_video), ", ".join(cls.cameras) or "-")
    console.print(sims)


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"
