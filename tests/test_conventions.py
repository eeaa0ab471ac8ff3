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


# -- errors name the API's parameters; the command line names its flags --------------------

@pytest.mark.parametrize("call, message", [
    (lambda api: api.run(task=8, method="nope", llm="replay"),
     "method: unknown method 'nope' (available: "),
    (lambda api: api.run(task=8, simulator="gazebo", llm="replay"),
     "simulator: unknown simulator 'gazebo' (available: "),
    (lambda api: api.Table.parse("120x80"),
     "table: 120 x 80 m is not a dining table (each side between 0.3 and 10 m); did you mean "
     "120x80cm?"),
    (lambda api: api.plan(task=8, feasibility="optimistic", llm="replay"),
     "feasibility: unknown profile 'optimistic'; choose from "),
    (lambda api: api.GropOptions(fidelity_w_s_per_cm=-1.0),
     "fidelity_weight: must be a finite number >= 0 (seconds per centimetre), got -1"),
    (lambda api: api.run(task=8, m=0, llm="replay"), "m=0: must be at least 1"),
    (lambda api: api.create_simulator("kinematic2d", grasp="suction"),
     "grasp='suction': needs the mujoco simulator (got 'kinematic2d')"),
])
def test_api_errors_name_the_api_parameters(call, message: str) -> None:
    from types import SimpleNamespace

    import llm_grop
    from llm_grop.planning.utility import GropOptions
    from llm_grop.simulation.registry import create_simulator

    api = SimpleNamespace(run=llm_grop.run, plan=llm_grop.plan, Table=llm_grop.Table,
                          GropOptions=GropOptions, create_simulator=create_simulator)
    with pytest.raises(ValueError) as caught:
        call(api)
    assert str(caught.value).startswith(message)
    assert "--" not in str(caught.value).split(":")[0]


@pytest.mark.parametrize("argv, line", [
    (["run", "--task", "8", "--method", "nope"], "--method: unknown method 'nope' (available: "),
    (["run", "--task", "8", "--table", "120x80"], "--table: 120 x 80 m is not a dining table"),
    (["run", "--task", "8", "--fidelity-weight", "inf"],
     "--fidelity-weight inf: expected a finite number"),
    (["run", "--task", "8", "--grasp", "friction"],
     "--grasp friction: needs the mujoco simulator (got 'kinematic2d')"),
    (["bench", "--methods", "grop,nope", "--out", "{tmp}/b"], "--methods: unknown method 'nope'"),
    (["bench", "--tasks", "1", "--prefer", "the mug near the plate", "--out", "{tmp}/b"],
     "--prefer: task 1: 'the mug near the plate': cannot read it as a relation"),
])
def test_the_command_line_names_its_flags(argv: list[str], line: str, tmp_path, capsys) -> None:
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    empty = tmp_path / "calls.jsonl"  # an empty recording: no model is loaded
    empty.touch()
    assert main([*argv, "--llm", "replay", "--replay", str(empty), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"llm-grop: error: {line}") and "\n" not in err


def test_an_error_keeps_its_parameter_through_pickling() -> None:
    import pickle

    from llm_grop.errors import BadInput, LLMUnavailable, UnknownObject

    for exc in (BadInput("not empty", param="out", value="runs/x"),
                LLMUnavailable("3 trials got no answer", param="max_failed", value=3),
                BadInput("plain"), UnknownObject("spork", ["spoon"], "task 3: objects")):
        back = pickle.loads(pickle.dumps(exc))
        assert (type(back), str(back), back.param, back.value, back.detail) == \
            (type(exc), str(exc), exc.param, exc.value, exc.detail)
    assert str(BadInput("not empty", param="out", value="runs/x")) == "out='runs/x': not empty"
    assert str(BadInput("too many", param="max_failed", value=3)) == "max_failed=3: too many"


# -- run and arrange use the LLM answer cache, as bench does ---------------------------------

@pytest.mark.parametrize("command", ["arrange", "run"])
def test_run_and_arrange_answer_from_the_llm_cache(command: str, chat_server, tmp_path,
                                                    capsys) -> None:
    import json

    from scripted import TASK1_GOOD, scripted

    chat_server.reply = scripted([TASK1_GOOD])
    cache = tmp_path / "cache"
    argv = [command, "a dinner plate, a dinner fork and a dinner knife", "--llm", "openai",
            "--base-url", chat_server.url, "--json", str(tmp_path / "out.json"), "-q"]

    def asked(*extra: str) -> tuple[int, object]:
        before = len(chat_server.requests)
        assert main([*argv, *extra]) == 0, capsys.readouterr().err
        doc = json.loads((tmp_path / "out.json").read_text())
        placed = doc["objects"] if command == "arrange" else doc["final"]["objects"]
        return len(chat_server.requests) - before, placed

    first, made = asked("--cache-dir", str(cache))
    assert first > 0 and any(cache.rglob("*.json"))
    again, remade = asked("--cache-dir", str(cache))
    assert again == 0 and remade == made  # every call answered from the cache, same result
    assert asked("--cache-dir", str(cache), "--no-cache")[0] == first
    assert asked()[0] == first  # the default cache ($LLM_GROP_CACHE_DIR in the tests) is fresh
    assert asked()[0] == 0


def test_a_cache_dir_that_is_a_file_is_refused_before_work(tmp_path, capsys) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["arrange", "a dinner plate", "--cache-dir", str(blocker), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("llm-grop: error: ") and "--cache-dir" in err and "is a file" in err
    assert "\n" not in err
