"""The paper's Table I tasks and user task files."""

from __future__ import annotations

from pathlib import Path

import pytest

from llm_grop.errors import BadInput
from llm_grop.language.request import parse_request
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import items_from_names
from llm_grop.world.tasks import Task, default_request, get_task, load_tasks

TABLE_I = {
    1: ("dinner plate", "dinner fork", "dinner knife"),
    2: ("bread plate", "water cup", "bread"),
    3: ("mug", "bread plate", "mug mat"),
    4: ("fruit bowl", "mug", "strawberry"),
    5: ("mug", "dinner plate", "mug lid"),
    6: ("dinner plate", "dinner fork", "mug", "mug lid"),
    7: ("dinner plate", "dinner fork", "dinner knife", "strawberry"),
    8: ("dinner plate", "dinner fork", "dinner knife", "mug", "mug lid"),
}


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "tasks.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def test_packaged_tasks_are_table_i() -> None:
    tasks = load_tasks()
    assert {n: t.objects for n, t in tasks.items()} == TABLE_I
    assert all("paper" in t.tags for t in tasks.values())
    assert sorted(n for n, t in tasks.items() if "smoke" in t.tags) == [1, 8]
    assert tasks[1].request == "set the table with a dinner plate, a dinner fork and a dinner knife"


@pytest.mark.parametrize("n", sorted(TABLE_I))
def test_each_task_request_asks_for_exactly_its_objects(n: int) -> None:
    catalog = Catalog.load(use_env=False)
    task = get_task(n, load_tasks())
    from_request = parse_request(task.request, catalog).items
    from_objects = items_from_names(task.objects, catalog)
    assert sorted(i.name for i in from_request) == sorted(i.name for i in from_objects)
    assert [i.kind for i in from_objects] == list(TABLE_I[n])


def test_get_task_unknown_lists_valid_ids() -> None:
    expected = r"^task 9: no such task; valid ids: 1, 2, 3, 4, 5, 6, 7, 8$"
    with pytest.raises(BadInput, match=expected):
        get_task(9, load_tasks())


def test_user_file_adds_and_replaces_tasks(tmp_path: Path) -> None:
    path = write(tmp_path, """
tasks:
  - id: 9
    objects: [dinner plate, salad fork, dinner fork]
    tags: [mine]
  - id: 2
    objects: [mug]
    request: just a mug
""")
    tasks = load_tasks([path])
    assert list(tasks) == [1, 2, 3, 4, 5, 6, 7, 8, 9]
    assert tasks[9] == Task(9, ("dinner plate", "salad fork", "dinner fork"), ("mine",),
                            "set the table with a dinner plate, a salad fork and a dinner fork")
    assert tasks[2].objects == ("mug",)
    assert tasks[2].request == "just a mug"
    assert load_tasks()[2].objects == TABLE_I[2]


def test_default_request_uses_an_before_vowels() -> None:
    assert default_request(["empty glass"]) == "set the table with an empty glass"


@pytest.mark.parametrize(("text", "message"), [
    ("tasks: [\n  - id: 1\n    objects: [mug\n", r"line \d+: not valid YAML"),
    ("tasks:\n  - id: 10\n", r"tasks\[0\] \(id 10\)\.objects: required, but missing"),
    ("tasks:\n  - id: 10\n    objects: []\n", r"tasks\[0\] \(id 10\)\.objects: must not be empty"),
    ("tasks:\n  - id: 0\n    objects: [mug]\n",
     r"tasks\[0\] \(id 0\)\.id: must be at least 1, got 0"),
    ("tasks:\n  - id: '3'\n    objects: [mug]\n",
     r"tasks\[0\] \(id '3'\)\.id: expected a whole number, got '3'"),
    ("tasks:\n  - id: 10\n    objects: [mug, '']\n", r"tasks\[0\] \(id 10\)\.objects\[1\]"),
    ("tasks:\n  - id: 10\n    objects: [mug]\n    colour: red\n",
     r"tasks\[0\] \(id 10\)\.colour: unknown key; expected one of id, objects"),
    ("tasks:\n  - id: 10\n    objects: [mug]\n  - id: 10\n    objects: [cup]\n",
     r"tasks\[1\]\.id: task 10 is defined twice"),
    ("- id: 1\n", "top level: expected a mapping with a .tasks. list"),
    ("", "top level: expected a mapping"),
])
def test_malformed_task_files_name_file_and_field(tmp_path: Path, text: str, message: str
                                                  ) -> None:
    path = write(tmp_path, text)
    with pytest.raises(BadInput, match=message) as info:
        load_tasks([path])
    assert str(info.value).startswith(f"tasks {path}")
    assert "\n" not in str(info.value)


def test_missing_task_file_is_bad_input(tmp_path: Path) -> None:
    with pytest.raises(BadInput, match=r"nope\.yaml: cannot read"):
        load_tasks([tmp_path / "nope.yaml"])
