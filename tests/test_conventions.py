"""What a newcomer expects from the command line and the Python API (issue 28): ``-h`` on
every command, help text on every option, and bad input that is a ``ValueError``."""

from __future__ import annotations

import click
import pytest

from llm_grop.cli import cli, main


def _commands(group: click.Group = cli, path: tuple[str, ...] = ()
              ) -> list[tuple[tuple[str, ...], click.Command]]:
    found: list[tuple[tuple[str, ...], click.Command]] = [(path, group)]
    for name, sub in sorted(group.commands.items()):
        if isinstance(sub, click.Group):
            found += _commands(sub, (*path, name))
        else:
            found.append(((*path, name), sub))
    return found


@pytest.mark.parametrize("path", [p for p, _ in _commands()], ids=lambda p: " ".join(p) or "-")
def test_dash_h_gives_help_on_every_command(path: tuple[str, ...], capsys) -> None:
    assert main([*path, "-h"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("Usage: llm-grop") and "-h, --help" in out


def test_every_option_has_help_text() -> None:
    missing = [(" ".join(path), p.opts[0]) for path, command in _commands()
               for p in command.params
               if isinstance(p, click.Option) and not p.hidden and not p.help]
    assert not missing


def test_bad_input_through_the_api_is_a_value_error() -> None:
    import llm_grop

    with pytest.raises(ValueError, match="unknown method 'nope'"):
        llm_grop.run(task=8, method="nope", llm="replay")
    with pytest.raises(ValueError, match="saucer"):
        llm_grop.understand("a dinner plate and a flying saucer", llm=None)
    assert not issubclass(llm_grop.Infeasible, ValueError)
