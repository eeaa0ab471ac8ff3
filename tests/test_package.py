"""The package as a newcomer meets it: ``python -m llm_grop``, the top-level names, typing,
``llm-grop schema``, ``llm-grop plugins`` and ``-v``."""

from __future__ import annotations

import json
import subprocess
import sys
from importlib import resources

import pytest

import llm_grop
from cli_support import REQUEST
from cli_support import one_line_error as _one_line_error
from llm_grop.cli import main
from llm_grop.contract.schemas import json_schema


def test_python_dash_m_runs_the_command() -> None:
    done = subprocess.run([sys.executable, "-m", "llm_grop", "--version"],
                          capture_output=True, text=True, check=True)
    assert done.stdout.startswith("llm-grop, version ") and llm_grop.__version__ in done.stdout


def test_every_public_name_imports_from_the_top() -> None:
    for name in llm_grop.__all__:
        assert getattr(llm_grop, name) is not None, name
    from llm_grop import BackendOptions, Table, arrange, run  # noqa: F401
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        llm_grop.nope  # noqa: B018


def test_import_is_cheap() -> None:
    code = ("import sys, llm_grop; print(sorted(m for m in ('clingo', 'ompl', 'matplotlib', "
            "'llm_grop.api') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert done.stdout.strip() == "[]"


def test_the_package_is_typed() -> None:
    assert resources.files("llm_grop").joinpath("py.typed").is_file()


@pytest.mark.parametrize("name", ["arrangement", "run", "trial"])
def test_schema_command_prints_the_schema(name: str, capsys) -> None:
    assert main(["schema", name]) == 0
    assert json.loads(capsys.readouterr().out) == json_schema(name)


def test_schema_command_refuses_an_unknown_document(capsys) -> None:
    assert main(["schema", "plans"]) == 2
    assert "'plans' is not one of 'arrangement', 'plan', 'run', 'trial'" in \
        _one_line_error(capsys)



def test_plugins_command_lists_every_kind(capsys) -> None:
    assert main(["plugins"]) == 0
    out = capsys.readouterr().out
    for text in ("--llm embedded", "--method llm-grop", "--simulator kinematic2d"):
        assert text in out


def test_verbose_logs_each_step_to_stderr(capsys) -> None:
    assert main(["-v", "run", REQUEST, "--method", "grop", "--chairs", "0", "-q"]) == 0
    err = capsys.readouterr().err
    assert "llm-grop: info: llm_grop.methods.episode: executing the plan" in err
    assert main(["run", REQUEST, "--method", "grop", "--chairs", "0", "-q"]) == 0
    assert capsys.readouterr().err == ""
