"""The object catalog: packaged objects, synonyms, plurals, user files and their errors."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from llm_grop.errors import CatalogError, UnknownObject
from llm_grop.world.catalog import CATALOG_ENV, Catalog, normalize_name, singular_forms

# From /work/shared/design/place-setting.md: name -> (shape, size [m], height [m]).
PLACE_SETTING = {
    "dinner plate": ("circle", (0.27, 0.27), 0.025),
    "bread plate": ("circle", (0.16, 0.16), 0.02),
    "salad plate": ("circle", (0.21, 0.21), 0.02),
    "fruit bowl": ("circle", (0.18, 0.18), 0.07),
    "soup bowl": ("circle", (0.16, 0.16), 0.06),
    "dinner fork": ("box", (0.025, 0.20), 0.02),
    "salad fork": ("box", (0.025, 0.17), 0.02),
    "dinner knife": ("box", (0.02, 0.23), 0.01),
    "butter knife": ("box", (0.02, 0.16), 0.01),
    "soup spoon": ("box", (0.035, 0.18), 0.02),
    "teaspoon": ("box", (0.03, 0.15), 0.02),
    "water cup": ("circle", (0.08, 0.08), 0.12),
    "wine glass": ("circle", (0.08, 0.08), 0.20),
    "mug": ("circle", (0.09, 0.09), 0.10),
    "mug mat": ("circle", (0.11, 0.11), 0.005),
    "mug lid": ("circle", (0.095, 0.095), 0.02),
    "strawberry": ("circle", (0.035, 0.035), 0.035),
    "bread": ("box", (0.10, 0.08), 0.05),
    "napkin": ("box", (0.12, 0.20), 0.01),
}
TABLE_I_OBJECTS = ["dinner plate", "dinner fork", "dinner knife", "bread plate", "water cup",
                   "bread", "mug", "mug mat", "fruit bowl", "strawberry", "mug lid"]
SPORK = "  - name: spork\n    shape: box\n    size: [0.03, 0.16]\n    height: 0.02\n"


@pytest.fixture(scope="module")
def catalog() -> Catalog:
    return Catalog.load(use_env=False)


def write(tmp_path: Path, text: str, name: str = "mine.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("name", TABLE_I_OBJECTS)
def test_every_table_i_object_is_in_the_catalog(name: str, catalog: Catalog) -> None:
    assert name in catalog.names()


@pytest.mark.parametrize("name", sorted(PLACE_SETTING))
def test_sizes_match_the_place_setting_notes(name: str, catalog: Catalog) -> None:
    shape, size, height = PLACE_SETTING[name]
    spec = catalog.specs[name]
    assert (spec.shape, spec.size, spec.height) == (shape, pytest.approx(size), height)


@pytest.mark.parametrize(("text", "name"), [
    ("fork", "dinner fork"), ("cup", "water cup"), ("teacup", "mug"), ("coaster", "mug mat"),
    ("Plate", "dinner plate"), ("the knife", "dinner knife"), ("teacup mat", "mug mat"),
    ("teacup lid", "mug lid"), ("Dinner-Plate", "dinner plate"),
])
def test_synonyms(text: str, name: str, catalog: Catalog) -> None:
    spec = catalog.lookup(text)
    assert spec is not None and spec.name == name


@pytest.mark.parametrize(("text", "name"), [
    ("knives", "dinner knife"), ("strawberries", "strawberry"), ("glasses", "water cup"),
    ("dinner plates", "dinner plate"), ("forks", "dinner fork"), ("mug lids", "mug lid"),
    ("loaves", "bread"),
])
def test_plurals(text: str, name: str, catalog: Catalog) -> None:
    spec = catalog.lookup(text)
    assert spec is not None and spec.name == name


def test_singular_forms_and_normalize_name() -> None:
    assert "dinner knife" in singular_forms("dinner knives")
    assert "strawberry" in singular_forms("strawberries")
    assert singular_forms("glass") == ["glass"]
    assert normalize_name("  A  Dinner-Plate! ") == "dinner plate"


def test_unknown_names(catalog: Catalog) -> None:
    assert catalog.lookup("spork") is None
    assert "spork" not in catalog
    with pytest.raises(UnknownObject, match=r"^task 1: unknown object 'spork'; did you mean"):
        catalog.resolve("spork", where="task 1")


@pytest.mark.parametrize(("typo", "best"), [
    ("dinner plat", "dinner plate"), ("strawbery", "strawberry"), ("mug lit", "mug lid"),
    ("diner knife", "dinner knife"), ("spork", "dinner fork"),
])
def test_suggestions_for_typos(typo: str, best: str, catalog: Catalog) -> None:
    suggestions = catalog.suggest(typo)
    assert suggestions[0] == best
    assert len(suggestions) == len(set(suggestions)) <= 3


def test_user_file_adds_and_overrides(tmp_path: Path, catalog: Catalog) -> None:
    path = write(tmp_path, "objects:\n" + SPORK + "    synonyms: [foon]\n"
                 "  - name: Dinner Plate\n    shape: circle\n    size: [0.3, 0.3]\n"
                 "    height: 0.03\n")
    mine = Catalog.load([path], use_env=False)
    assert len(mine) == len(catalog) + 1
    assert mine.resolve("foons").name == "spork"
    assert mine.specs["spork"].size == (0.03, 0.16)
    assert mine.specs["dinner plate"].size == (0.3, 0.3)
    assert catalog.specs["dinner plate"].size == (0.27, 0.27)


def test_later_files_override_earlier_ones(tmp_path: Path) -> None:
    first = write(tmp_path, "objects:\n" + SPORK, "a.yaml")
    second = write(tmp_path, "objects:\n" + SPORK.replace("0.16]", "0.18]"), "b.yaml")
    assert Catalog.load([first, second], use_env=False).specs["spork"].size == (0.03, 0.18)


def test_environment_variable_adds_files(tmp_path: Path, monkeypatch: pytest.MonkeyPatch
                                         ) -> None:
    a = write(tmp_path, "objects:\n" + SPORK, "a.yaml")
    b = write(tmp_path, "objects:\n" + SPORK.replace("spork", "chopstick"), "b.yaml")
    monkeypatch.setenv(CATALOG_ENV, os.pathsep.join([str(a), str(b)]))
    assert {"spork", "chopstick"} <= set(Catalog.load().names())
    assert "spork" not in Catalog.load(use_env=False).names()


def test_explicit_files_override_the_environment(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    env = write(tmp_path, "objects:\n" + SPORK, "env.yaml")
    cli = write(tmp_path, "objects:\n" + SPORK.replace("0.16]", "0.2]"), "cli.yaml")
    monkeypatch.setenv(CATALOG_ENV, str(env))
    assert Catalog.load([cli]).specs["spork"].size == (0.03, 0.2)


@pytest.mark.parametrize(("text", "field", "message"), [
    ("objects: [\n  - name: x\n", "line 2", "not valid YAML"),
    ("objects:\n  - name: spork\n    size: [0.02, 0.15]\n    height: 0.01\n",
     "objects[0] ('spork').shape", "required, but missing"),
    ("objects:\n" + SPORK.replace("[0.03", "[-0.03"), "objects[0] ('spork').size",
     "size must be positive"),
    ("objects:\n" + SPORK.replace("[0.03", "[.nan"), "objects[0] ('spork').size",
     "size must be positive"),
    ("objects:\n" + SPORK.replace("height: 0.02", "height: .inf"),
     "objects[0] ('spork').height", "finite"),
    ("objects:\n" + SPORK + SPORK.replace("spork", "saucer").replace("box", "circle"),
     "objects[1] ('saucer').size", "a circle needs size [d, d]"),
    ("objects:\n" + SPORK + "    colour: red\n", "objects[0] ('spork').colour",
     "unknown key; expected one of name, shape, size, height, synonyms"),
    ("objects:\n" + SPORK + "    hieght: 0.02\n", "objects[0] ('spork').hieght",
     "unknown key; did you mean 'height'?"),
    ("objects:\n" + SPORK.replace("box", "star"), "objects[0] ('spork').shape",
     "'circle' or 'box'"),
    ("objects:\n" + SPORK.replace("spork", "'!!'"), "objects[0] ('!!').name",
     "needs letters or digits"),
    ("- spork\n", "top level", "expected a mapping"),
    ("", "top level", "expected a mapping"),
])
def test_malformed_user_files(tmp_path: Path, text: str, field: str, message: str) -> None:
    path = write(tmp_path, text)
    with pytest.raises(CatalogError) as info:
        Catalog.load([path], use_env=False)
    text = str(info.value)
    assert text.startswith(f"catalog {path}")
    assert field in text and message in text
    assert "\n" not in text


def test_unreadable_user_file(tmp_path: Path) -> None:
    with pytest.raises(CatalogError, match=r"missing\.yaml: cannot read"):
        Catalog.load([tmp_path / "missing.yaml"], use_env=False)


def _entry(name: str, synonyms: str = "[]", shape: str = "box") -> str:
    return (f"  - name: {name}\n    shape: {shape}\n    size: [0.03, 0.03]\n"
            f"    height: 0.02\n    synonyms: {synonyms}\n")


@pytest.mark.parametrize(("entries", "message"), [
    ([_entry("mug"), _entry("spork"), _entry("saucer"), _entry("Mug")],
     "objects[3] ('Mug'): duplicate name; objects[0] is already 'mug'"),
    ([_entry("water cup", "[cup]"), _entry("cup")],
     "objects[1] ('cup'): name 'cup' is already a synonym of objects[0] ('water cup')"),
    ([_entry("cup"), _entry("water cup", "[Cup]")],
     "objects[1] ('water cup').synonyms: 'Cup' is already the name of objects[0] ('cup')"),
    ([_entry("water cup", "[cup]"), _entry("mug", "[teacup, 'cup!']")],
     "objects[1] ('mug').synonyms: 'cup!' is already a synonym of objects[0] ('water cup')"),
])
def test_duplicate_names_within_one_file_are_refused(tmp_path: Path, entries: list[str],
                                                     message: str) -> None:
    path = write(tmp_path, "objects:\n" + "".join(entries))
    with pytest.raises(CatalogError) as info:
        Catalog.load([path], use_env=False)
    assert str(info.value) == f"catalog {path}: {message}"


def test_repeats_within_one_entry_are_harmless(tmp_path: Path) -> None:
    path = write(tmp_path, "objects:\n" + _entry("spork", "[spork, foon, Foon, '!!']")
                 + _entry("chopstick", "['??']"))
    mine = Catalog.load([path], use_env=False)
    assert mine.resolve("foon").name == "spork"


def test_a_user_file_may_reuse_packaged_names_and_synonyms(tmp_path: Path,
                                                          catalog: Catalog) -> None:
    # Between files a later one overrides by name; only duplicates inside one file fail.
    path = write(tmp_path, "objects:\n" + _entry("mug", "[teacup]", "circle")
                 + _entry("cup", "[fork]"))
    mine = Catalog.load([path], use_env=False)
    assert mine.specs["mug"].size == (0.03, 0.03)
    assert mine.resolve("cup").name == "cup"
    assert mine.resolve("fork").name == catalog.resolve("fork").name


def test_from_text_reads_one_file_alone() -> None:
    mine = Catalog.from_text("objects:\n" + SPORK, "mine.yaml")
    assert mine.names() == ["spork"]
    with pytest.raises(CatalogError, match=r"^mine\.yaml: objects\[1\] \('spork'\): "
                                           r"duplicate name"):
        Catalog.from_text("objects:\n" + SPORK + SPORK, "mine.yaml")


# Found by fuzzing (tests/fuzz, benchmarks/fuzz.py): each used to escape as another
# exception type or a message over two lines.

def test_a_user_file_that_is_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "mine.yaml"
    path.write_bytes(b"objects: [\xff\xfe]\n")
    with pytest.raises(CatalogError, match=r"mine\.yaml: cannot read \(not UTF-8 text\)$"):
        Catalog.load([path], use_env=False)


@pytest.mark.parametrize("text", ["objects: !!int 0x\n", "objects: !!timestamp 2024-13-45\n",
                                  "objects: !!timestamp\n", "objects: !!bool maybe\n",
                                  "objects: !!int\n", "objects: !!float\n",
                                  "objects: !!float abc\n"])
def test_tagged_values_yaml_cannot_convert(text: str) -> None:
    with pytest.raises(CatalogError, match=r"^c\.yaml: not valid YAML"):
        Catalog.from_text(text, "c.yaml")


def test_a_field_name_with_a_line_break_stays_on_one_line() -> None:
    text = 'objects: [{name: spork, shape: box, size: [1, 1], height: 1, "x\\ny": 1}]\n'
    with pytest.raises(CatalogError) as info:
        Catalog.from_text(text, "c.yaml")
    assert str(info.value) == ("c.yaml: objects[0] ('spork').'x\\ny': unknown key; expected "
                               "one of name, shape, size, height, synonyms, stack")


def test_plates_and_bowls_may_wait_in_piles() -> None:
    catalog = Catalog.load(use_env=False)
    assert catalog.resolve("dinner plate").stack == 6
    assert catalog.resolve("fruit bowl").stack == 4
    assert catalog.resolve("water cup").stack == 1
    text = "objects: [{name: spork, shape: box, size: [1, 1], height: 1, stack: 0}]\n"
    with pytest.raises(CatalogError, match=r"objects\[0\] \('spork'\).stack: "):
        Catalog.from_text(text, "c.yaml")
