"""The one settings record: every front door is a view of it, and a bad value is named in
the words of the door it came through."""

from __future__ import annotations

import json
from pathlib import Path

import click
import pytest

from llm_grop.cli import cli, main
from llm_grop.errors import BadInput
from llm_grop.settings import DEFAULTS, RunSettings, door, fields, flag, help_text, label

#: Flags users had before the settings record; each must still set its field.
LEGACY_FLAGS = {
    "run": ["--task", "--scene", "--method", "--seed", "--chairs", "--table", "--simulator",
            "--grasp", "--truth", "--feasibility", "--weight", "--fidelity-weight",
            "--manip-attempts", "--nav-attempts", "--llm", "--model", "--base-url",
            "--replay", "--timeout", "--max-answer-bytes", "--retries", "--catalog",
            "--configurations", "-m", "--attempts", "--zero-shot", "--notes", "--prefer",
            "--preferences", "--temperature", "--top-p", "--max-tokens",
            "--frequency-penalty", "--presence-penalty", "--cache-dir", "--no-guess"],
    "bench": ["--seed", "--scene", "--chairs", "--table", "--simulator", "--grasp", "--truth",
              "--feasibility", "--weight", "--fidelity-weight", "--task-file", "--llm",
              "--configurations", "--prefer", "--preferences", "--cache-dir"],
    "arrange": ["--task", "--table", "--seed", "--llm", "--configurations", "--no-guess",
                "--cache-dir"],
}


def _options(command: str) -> dict[str, click.Option]:
    return {opt: p for p in cli.commands[command].params if isinstance(p, click.Option)
            for opt in p.opts}


def test_every_field_has_help_a_group_and_a_default() -> None:
    for name in fields():
        assert help_text(name), name
        assert RunSettings.model_fields[name].json_schema_extra["group"], name  # type: ignore
    assert RunSettings() == DEFAULTS


@pytest.mark.parametrize("command", sorted(LEGACY_FLAGS))
def test_flags_are_the_records_fields(command: str) -> None:
    options = _options(command)
    for legacy in LEGACY_FLAGS[command]:
        assert legacy in options, f"{command} lost {legacy}"
    for opt in options.values():
        if opt.name not in RunSettings.model_fields:
            continue
        info = RunSettings.model_fields[opt.name]
        assert flag(opt.name) in opt.opts
        if opt.name != "seed" and (command, opt.name) != ("bench", "chairs"):
            assert opt.help in (help_text(opt.name), door(opt.name).cli_help)
        if not opt.multiple and opt.name not in ("cache", "guess"):
            given = opt.default if type(opt.default).__name__ != "Sentinel" else None
            assert given == info.default, (command, opt.name)


def test_the_record_validates_and_names_the_field() -> None:
    with pytest.raises(BadInput) as caught:
        RunSettings.make(m=0)
    assert (caught.value.param, str(caught.value)) == ("m", "m=0: must be at least 1")
    with pytest.raises(BadInput, match=r"^mm: unknown setting; did you mean 'm'\?"):
        RunSettings.make(mm=3)
    with pytest.raises(BadInput, match="^weight=inf: expected a finite number"):
        RunSettings.make(weight=float("inf"))
    assert RunSettings.make(catalog_files=[Path("a.yaml")]).catalog_files == ("a.yaml",)


@pytest.mark.parametrize("where, words", [
    ("python", "m=0"), ("cli", "--configurations 0"), ("sweep", "m 0"), ("json", "m")])
def test_each_front_door_names_a_field_its_own_way(where, words) -> None:
    assert label("m", where, 0 if where != "json" else None) == words  # type: ignore[arg-type]


def test_the_same_bad_value_through_every_door(tmp_path: Path, capsys) -> None:
    import llm_grop
    from llm_grop.service.models import PlanBody, one_line

    with pytest.raises(ValueError, match="^m=0: must be at least 1"):
        llm_grop.plan(task=1, m=0)
    assert main(["run", "--task", "1", "-m", "0", "-q"]) == 2
    assert "'--configurations' / '-m': 0 is not in the range x>=1" in capsys.readouterr().err
    sweep = tmp_path / "s.yaml"
    sweep.write_text("m: 0\n")
    assert main(["sweep", str(sweep), "--out", str(tmp_path / "o"), "-q"]) == 2
    assert capsys.readouterr().err.strip() == f"llm-grop: error: {sweep}: m: must be at " \
                                              "least 1, got 0"
    from pydantic import ValidationError

    with pytest.raises(ValidationError) as caught:
        PlanBody.model_validate({"task": 1, "m": 0})
    assert one_line(caught.value.errors(), {"task": 1, "m": 0}, PlanBody, where=None) == \
        "m: must be at least 1, got 0"


def test_settings_mentioned_in_messages_are_worded_per_door() -> None:
    from llm_grop.cli.flags import cli_words
    from llm_grop.settings import words

    text = "the request names no object, and guess=False forbids it (chairs=N)"
    assert cli_words(text) == "the request names no object, and --no-guess forbids it " \
                              "(--chairs N)"
    assert words(text, "json") == 'the request names no object, and "guess": false forbids ' \
                                  'it ("chairs": N)'
    assert words("out=x is no setting", "cli") == "out=x is no setting"


def test_sweep_files_take_every_setting_by_its_name(tmp_path: Path) -> None:
    from llm_grop.cli.sweep import cell_settings
    from llm_grop.experiment.sweep import SWEPT, Values, load_sweep

    assert {"m", "nav_attempts", "grasp", "weight", "preferences", "prefer"} <= set(SWEPT)
    assert SWEPT["preferences"] == "preferences_file" and SWEPT["prefer"] == "preferences"
    assert set(SWEPT) <= set(Values.model_fields)
    (tmp_path / "p.yaml").write_text("preferences: []\n")
    sweep = tmp_path / "s.yaml"
    sweep.write_text("m: 5\npreferences: p.yaml\nllm: {backend: replay, replay: r.jsonl}\n"
                     "grid:\n  nav_attempts: [1, 2]\n")
    plan = load_sweep(sweep)
    made = [RunSettings.make(cell_settings(c.values, plan.base)) for c in plan.cells]
    assert [(s.m, s.nav_attempts, s.llm) for s in made] == [(5, 1, "replay"), (5, 2, "replay")]
    assert made[0].preferences_file == str(tmp_path / "p.yaml")
    assert made[0].replay == str(tmp_path / "r.jsonl")


def test_json_bodies_take_the_records_defaults_and_help() -> None:
    from llm_grop.service.models import ArrangeBody, PlanBody, RunBody

    for body in (ArrangeBody, PlanBody, RunBody):
        for name in ("seed", "m", "guess"):
            f = body.model_fields[name]
            assert (f.default, f.description) == (getattr(DEFAULTS, name), help_text(name))
    assert RunBody.model_fields["simulator"].default == DEFAULTS.simulator


def test_component_records_given_whole_are_lifted_into_the_record() -> None:
    from llm_grop.arrangement.pipeline import ArrangeOptions
    from llm_grop.assembly import arrange_options, planner_options, settle
    from llm_grop.llm.base import SamplingParams
    from llm_grop.planning.utility import GropOptions

    s, bases = settle(None, {"options": ArrangeOptions(m=3, params=SamplingParams(0.5),
                                                       preference_pool=("x",)),
                             "planner": GropOptions(w=7.0, alternatives=5), "seed": 2})
    assert (s.m, s.temperature, s.weight, s.seed) == (3, 0.5, 7.0, 2)
    assert arrange_options(s, bases.arrange).preference_pool == ("x",)
    assert planner_options(s, bases.planner).alternatives == 5
    named, _ = settle(None, {"options": ArrangeOptions(m=3), "m": 4})
    assert named.m == 4  # a field given by name wins


def test_a_record_and_keywords_give_the_same_run() -> None:
    import llm_grop
    from llm_grop.contract.run_json import run_to_dict

    def doc(result) -> dict:
        out = run_to_dict(result)
        out.pop("planning_time_s")
        return out

    settings = RunSettings.make(task=1, method="grop", seed=3, chairs=2, nav_attempts=2)
    by_record = doc(llm_grop.run(settings=settings))
    assert by_record == doc(llm_grop.run(task=1, method="grop", seed=3, chairs=2,
                                         nav_attempts=2))
    assert json.loads(json.dumps(by_record))["seed"] == 3


def test_the_record_publishes_a_json_schema() -> None:
    schema = RunSettings.model_json_schema()
    assert schema["properties"]["m"]["door"] == {"cli": "--configurations", "short": "-m"}
    assert schema["properties"]["m"]["minimum"] == 1
    assert schema["additionalProperties"] is False


def test_the_diners_setting_is_bounded_as_a_request_is() -> None:
    # The settings record sits below world, so it spells the bound out; they must agree.
    from annotated_types import Le

    from llm_grop.settings import RunSettings
    from llm_grop.world.request import MAX_DINERS

    bounds = [m.le for m in RunSettings.model_fields["diners"].metadata if isinstance(m, Le)]
    assert bounds == [MAX_DINERS]

