"""``llm-grop learn`` as a user runs it: the learned file, what it prints, the output path
checked first, bad examples and contradictions, and ``arrange --preferences`` with it."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from cli_support import one_line_error
from learning_support import LEFT_HANDED, NO_CALLS, SETTING, USUAL, write_example
from llm_grop.arrangement.preferences import load_preference_file
from llm_grop.cli import main


@pytest.fixture(autouse=True)
def _no_user_catalog(monkeypatch) -> None:
    monkeypatch.delenv("LLM_GROP_CATALOG", raising=False)


@pytest.fixture
def examples(tmp_path: Path) -> list[Path]:
    return [write_example(tmp_path / f"left{k}.json", LEFT_HANDED, k) for k in range(2)]


def test_learn_writes_a_preferences_file_and_prints_it(tmp_path: Path, examples,
                                                       capsys) -> None:
    out = tmp_path / "prefs.yaml"
    assert main(["learn", *map(str, examples), "--out", str(out)]) == 0
    printed = capsys.readouterr()
    # No server answers here: --llm auto finds no capable model to generalise with.
    assert printed.err.startswith("warning: no capable model to generalise with")
    assert printed.err.count("\n") == 1
    assert "Learned from 2 examples" in printed.out and f"Wrote preferences: {out}" in printed.out
    sentences = load_preference_file(out)
    assert "the dinner fork 3.3 cm to the right of the dinner plate" in sentences
    text = out.read_text()
    assert text.startswith("# Preferences learned by `llm-grop learn` from 2 examples:\n"
                           f"#   {examples[0]}\n#   {examples[1]}\n")
    assert "to the right of the dinner plate  # 3.1 to 3.6 cm; " \
        f"{examples[0]}, {examples[1]}\n" in text


def test_arrange_with_the_learned_file_keeps_the_style(tmp_path: Path, examples,
                                                       capsys) -> None:
    prefs, arranged = tmp_path / "prefs.yaml", tmp_path / "new.json"
    assert main(["learn", *map(str, examples), "--out", str(prefs), "-q"]) == 0
    assert main(["arrange", SETTING, "--preferences", str(prefs), "--llm", "replay",
                 "--replay", str(NO_CALLS), "--seed", "9", "--json", str(arranged), "-q"]) == 0
    capsys.readouterr()
    relations = {(r["subject"], r["relation"], r["reference"], r["source"])
                 for r in json.loads(arranged.read_text())["relations"]}
    assert relations == {("dinner fork", "to the right of", "dinner plate", "preference"),
                         ("dinner knife", "to the left of", "dinner plate", "preference"),
                         ("mug", "above and to the left of", "dinner plate", "preference")}
    relearned = tmp_path / "again.yaml"
    assert main(["learn", str(arranged), "--out", str(relearned), "-q"]) == 0
    strip = [s.split(" cm ")[-1] for s in load_preference_file(prefs)]
    assert [s.split(" cm ")[-1] for s in load_preference_file(relearned)] == strip


def test_an_existing_out_file_is_kept_unless_forced(tmp_path: Path, examples, capsys) -> None:
    out = tmp_path / "prefs.yaml"
    out.write_text("preferences: [the dinner fork to the left of the dinner plate]\n")
    assert main(["learn", *map(str, examples), "--out", str(out)]) == 2
    assert one_line_error(capsys) == (f"llm-grop: error: --out {out}: already exists; give "
                                      "--force to replace it")
    assert "left of" in out.read_text()
    assert main(["learn", *map(str, examples), "--out", str(out), "--force", "-q"]) == 0
    assert "learned by" in out.read_text()


def test_the_out_path_is_checked_before_any_example_is_read(tmp_path: Path, capsys) -> None:
    out = tmp_path / "missing" / "prefs.yaml"
    assert main(["learn", str(tmp_path / "nope.json"), "--out", str(out)]) == 2
    assert one_line_error(capsys) == (f"llm-grop: error: --out {out}: directory "
                                      f"{out.parent} does not exist")


def test_a_bad_example_alone_is_one_line(tmp_path: Path, capsys) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text('{"table": {"size": [0.9, 0.6]}, "objects": []}')
    assert main(["learn", str(bad), "--out", str(tmp_path / "p.yaml")]) == 2
    assert one_line_error(capsys) == (f"llm-grop: error: {bad}: no objects; an example is a "
                                      "table setting")
    assert not (tmp_path / "p.yaml").exists()


def test_a_bad_example_among_good_ones_is_a_warning(tmp_path: Path, examples, capsys) -> None:
    missing = tmp_path / "missing.json"
    out = tmp_path / "p.yaml"
    assert main(["learn", str(examples[0]), str(missing), str(examples[1]),
                 "--out", str(out), "--exact"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == [f"warning: {missing}: cannot read (No such file or directory); skipped"]
    assert f"# Not learned:\n#   {missing}: cannot read" in out.read_text()
    assert main(["learn", *map(str, examples), "--out", str(out), "--force", "-q"]) == 0
    assert capsys.readouterr() == ("", "")


def test_contradicting_examples_are_warned_about(tmp_path: Path, monkeypatch,
                                                 capsys) -> None:
    monkeypatch.chdir(tmp_path)
    write_example(Path("left.json"), LEFT_HANDED, 0)
    write_example(Path("usual.json"), USUAL, 0)
    assert main(["learn", "left.json", "usual.json", "--out", "p.yaml", "--exact"]) == 0
    assert capsys.readouterr().err.splitlines() == [
        "warning: the examples disagree on where the dinner fork goes: to the right of the "
        "dinner plate in left.json; to the left of it in usual.json; not learned",
        "warning: the examples disagree on where the dinner knife goes: to the left of the "
        "dinner plate in left.json; to the right of it in usual.json; not learned",
        "warning: the examples disagree on where the mug goes: above and to the left of the "
        "dinner plate in left.json; above and to the right of it in usual.json; not learned"]
    assert load_preference_file("p.yaml") == (
        "the dinner plate 3.5 cm from the diner's edge of the table",)
    assert "#   the examples disagree on where the mug goes: above and to the left of the " \
        "dinner plate in left.json; above and to the right of it in usual.json; not " \
        "learned\n" in Path("p.yaml").read_text()


def test_arrange_with_examples_keeps_the_style_and_says_where_it_was_learned(
        tmp_path: Path, examples) -> None:
    """``--examples`` learns as ``learn`` does and applies the sentences directly; each
    relation they give is ``learned``, with the settings it was read off."""
    out = tmp_path / "a.json"
    request = "a dinner plate, a dinner fork and a dinner knife"
    flags = [a for e in examples for a in ("--examples", str(e))]
    assert main(["arrange", request, *flags, "--llm", "replay", "--replay", str(NO_CALLS),
                 "--seed", "5", "--json", str(out), "-q"]) == 0
    doc = json.loads(out.read_text())
    got = {(r["subject"], r["relation"], r["reference"]): r for r in doc["relations"]}
    assert set(got) == {("dinner fork", "to the right of", "dinner plate"),
                        ("dinner knife", "to the left of", "dinner plate")}
    assert all(r["source"] == "learned" and r["examples"] == [str(e) for e in examples]
               for r in got.values())
    plate, fork = (next(o for o in doc["objects"] if o["name"] == n)
                   for n in ("dinner plate", "dinner fork"))
    assert fork["x"] > plate["x"]


def test_examples_that_disagree_are_a_warning_of_the_run(tmp_path: Path, capsys) -> None:
    mixed = [write_example(tmp_path / "left.json", LEFT_HANDED, 1),
             write_example(tmp_path / "usual.json", USUAL, 2)]
    out = tmp_path / "a.json"
    flags = [a for e in mixed for a in ("--examples", str(e))]
    prefs = ["--prefer", "the dinner fork 2 cm to the left of the dinner plate",
             "--prefer", "the dinner knife 2 cm to the right of the dinner plate"]
    assert main(["arrange", "a dinner plate, a dinner fork and a dinner knife", *flags,
                 *prefs, "--llm", "replay", "--replay", str(NO_CALLS), "--json", str(out),
                 "-q"]) == 0
    warnings = json.loads(out.read_text())["warnings"]
    assert any(w.startswith("--examples: the examples disagree on where the dinner fork")
               for w in warnings)


def test_a_bad_example_stops_arrange_before_any_work(tmp_path: Path, capsys) -> None:
    bad = tmp_path / "empty.json"
    bad.write_text("{}", encoding="utf-8")
    assert main(["arrange", SETTING, "--examples", str(bad), "--llm", "replay", "--replay",
                 str(NO_CALLS)]) == 2
    assert str(bad) in one_line_error(capsys)


def test_learn_generalises_with_a_model_from_a_server(tmp_path: Path, examples, chat_server,
                                                      capsys) -> None:
    chat_server.reply = lambda body: "Place the water cup above the dinner plate."
    out = tmp_path / "p.yaml"
    assert main(["learn", *map(str, examples), "--out", str(out), "--llm", "openai",
                 "--base-url", chat_server.url, "--model", "qwen2.5:7b"]) == 0
    assert capsys.readouterr().err == ""
    # The rule takes the examples' spacing (their median gap, centimetres).
    assert re.search(r"^  - the water cup \d+(\.\d)? cm above the dinner plate  "
                     r"# a rule by qwen2\.5:7b$", out.read_text(), re.M)


def test_a_preference_against_the_examples_names_both(tmp_path: Path, examples,
                                                      capsys) -> None:
    assert main(["arrange", SETTING, "--llm", "replay", "--replay", str(NO_CALLS),
                 *(a for e in examples for a in ("--examples", str(e))),
                 "--prefer", "the dinner fork to the left of the dinner plate"]) == 2
    error = one_line_error(capsys)
    assert "the preferences and the examples contradict each other" in error, error
