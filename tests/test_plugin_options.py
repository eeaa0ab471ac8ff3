"""Plugins' own options: each simulator, LLM backend and method declares an ``Options``
dataclass, the front doors carry a user's values to it (``--sim-option``,
``--llm-option``, ``--method-option``, a sweep file, JSON), and the registry checks them."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pytest

from llm_grop.arrangement.random_placement import TRUNCATION_M, random_configurations
from llm_grop.assembly import call_log, check_backend, make_backend
from llm_grop.errors import BadInput
from llm_grop.geometry.places import places
from llm_grop.llm.base import SamplingParams
from llm_grop.llm.registry import BACKENDS, backend_options_class, create_llm
from llm_grop.methods.registry import METHODS, get_method
from llm_grop.settings import RunSettings
from llm_grop.settings.declared import NoOptions, declared_options, option_names, path_options
from llm_grop.simulation.registry import SIMULATORS, simulator_class
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import items_from_names
from llm_grop.world.table import Table

if TYPE_CHECKING:
    from conftest import ChatServer


@pytest.fixture(autouse=True)
def _no_ambient_openai_env(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    for name in ("OPENAI_BASE_URL", "OPENAI_API_KEY"):
        monkeypatch.delenv(name, raising=False)
    yield


def _declared() -> list[tuple[str, str, type]]:
    out = [("backend", n, backend_options_class(n)) for n in BACKENDS.names()]
    out += [("method", n, METHODS.get(n).Options) for n in METHODS.names()]
    out += [("simulator", n, simulator_class(n).Options) for n in SIMULATORS.names()]
    return out


@pytest.mark.parametrize(("kind", "name", "options"), _declared(),
                         ids=[f"{k}-{n}" for k, n, _ in _declared()])
def test_every_plugin_declares_options_whose_defaults_check(kind: str, name: str,
                                                            options: type) -> None:
    made = declared_options(options, {}, owner=f"{kind} {name!r}", param="x")
    assert isinstance(made, options)
    assert option_names(options) == tuple(vars(made)) or options is NoOptions


def test_an_undeclared_backend_option_is_one_line_naming_it() -> None:
    with pytest.raises(BadInput) as err:
        check_backend(RunSettings(llm="embedded", backend_options={"nope": 1}))
    assert err.value.param == "backend_options.nope"
    assert "LLM backend 'embedded' has no option 'nope' (its options: context_tokens)" \
        in str(err.value)
    with pytest.raises(BadInput) as err:
        create_llm("embedded", own={"context_tokens": 8})
    assert err.value.param == "backend_options.context_tokens"
    assert "must be at least 256" in str(err.value)


def test_the_embedded_context_window_is_an_option_and_part_of_the_cache_key() -> None:
    # Nothing is loaded: the model loads on the first call.
    default = create_llm("embedded")
    wide = make_backend(RunSettings(llm="embedded", backend_options=["context_tokens=4096"]))
    assert wide.cache_identity != default.cache_identity
    assert wide.cache_identity.endswith(":ctx4096")


def test_openai_structured_output_can_be_turned_off(chat_server: ChatServer) -> None:
    schema = {"type": "object", "properties": {"x": {"type": "integer"}}}
    params = SamplingParams(seed=1)
    for given, sent in (((), True), (("structured_output=false",), False)):
        settings = RunSettings(llm="openai", base_url=chat_server.url,
                               backend_options=given)
        log = call_log(make_backend(settings))
        log.complete("Where does the fork go?", params, schema=schema)
        assert ("response_format" in chat_server.requests[-1]) is sent
        assert log.llm.supports_schema is sent


def test_the_baselines_draw_in_the_diners_whole_place_when_asked() -> None:
    items = items_from_names(["dinner plate", "dinner fork", "dinner knife", "mug", "mug lid"],
                             Catalog.load())
    table = Table()
    centre = places(table, table.seats)[0]

    def farthest(box: str) -> float:
        configs = random_configurations(items, table, np.random.default_rng(3), m=25,
                                        box=box)  # type: ignore[arg-type]
        return max(max(abs(p.x - centre.origin[0]), abs(p.y - centre.origin[1]))
                   for c in configs for p in c.placements)

    assert farthest("authors") <= TRUNCATION_M + 1e-9
    assert farthest("place") > TRUNCATION_M


def test_a_method_takes_only_the_options_it_declares() -> None:
    tpra = get_method("tpra", {"draw_box": "place"})
    assert tpra.options.draw_box == "place"  # type: ignore[attr-defined]
    assert tpra.arrangement.box == "place"  # type: ignore[attr-defined]
    with pytest.raises(BadInput) as err:
        get_method("llm-grop", {"draw_box": "place"})
    assert err.value.param == "method_options.draw_box"
    assert "method 'llm-grop' has no option 'draw_box' (it declares none)" in str(err.value)
    with pytest.raises(BadInput) as err:
        get_method("grop", {"draw_box": "room"})
    assert err.value.param == "method_options.draw_box"


def test_method_options_change_the_plan_and_the_identity() -> None:
    from llm_grop.api import plan

    default = plan(settings=RunSettings(task=6, method="tpra", seed=2))
    wide = plan(settings=RunSettings(task=6, method="tpra", seed=2,
                                     method_options={"draw_box": "place"}))
    assert default.settings.identity()["method_options"] == {}
    assert wide.settings.identity()["method_options"] == {"draw_box": "place"}
    assert wide.planned.arrangement.placements != default.planned.arrangement.placements


def test_file_options_are_known_so_a_network_door_can_refuse_them() -> None:
    assert path_options(simulator_class("mujoco").Options) == ("video_path",)
    assert path_options(simulator_class("kinematic2d").Options) == ()


@pytest.mark.parametrize(("flags", "words"), [
    (["--llm-option", "nope=1"],
     "--llm-option nope: LLM backend 'embedded' has no option 'nope'"),
    (["--llm-option", "context_tokens"], "--llm-option: expected KEY=VALUE"),
    (["--method", "tpra", "--method-option", "draw_box=room"],
     "--method-option draw_box=room: expected one of 'authors' or 'place'"),
])
def test_the_command_line_names_the_flag(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                         flags: list[str], words: str) -> None:
    from llm_grop.cli import main

    assert main(["run", "--task", "1", *flags, "--json", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and "\n" not in err and "Traceback" not in err
    assert not (tmp_path / "r.json").exists()


def test_a_sweep_file_carries_llm_and_method_options(tmp_path: Path) -> None:
    from llm_grop.cli.sweep import cell_settings
    from llm_grop.experiment.sweep import load_sweep

    path = tmp_path / "s.yaml"
    path.write_text("tasks: [1]\nmethods: [tpra]\ntrials: 1\n"
                    "llm: {backend: embedded, options: {context_tokens: 4096}}\n"
                    "sim_options: {truth: mujoco}\n"
                    "grid:\n  method_options: [{draw_box: authors}, {draw_box: place}]\n")
    sweep = load_sweep(path)
    made = [RunSettings.make(cell_settings(c.values, sweep.base)) for c in sweep.cells]
    assert sorted(dict(s.method_options)["draw_box"] for s in made) == ["authors", "place"]
    assert all(dict(s.backend_options) == {"context_tokens": 4096} for s in made)
    assert all(dict(s.sim_options) == {"truth": "mujoco"} for s in made)
