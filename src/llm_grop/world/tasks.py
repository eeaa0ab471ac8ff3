"""Named tasks: sets of objects to arrange, such as the paper's Table I.

The package ships ``data/tasks.yaml`` (tasks 1-8 of the paper); users add tasks
in files with the same layout, and a task whose id is already defined replaces it.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, StrictInt, StringConstraints

from llm_grop.datafile import load_yaml_model
from llm_grop.errors import BadInput

_Name = Annotated[str, StringConstraints(strip_whitespace=True, min_length=1)]


@dataclass(frozen=True)
class Task:
    """A task: ``objects`` (catalog names; a repeated name asks for two) to set on a table.

    ``tags`` group tasks (``paper``: the paper's Table I; ``smoke``: a quick subset);
    ``request`` is a sentence asking for the objects.
    """

    id: int
    objects: tuple[str, ...]
    tags: tuple[str, ...]
    request: str


class _TaskModel(BaseModel):
    model_config = ConfigDict(extra="forbid")

    id: StrictInt = Field(ge=1)
    objects: list[_Name] = Field(min_length=1)
    tags: list[_Name] = []
    request: _Name | None = None


class _TasksModel(BaseModel):
    model_config = ConfigDict(extra="forbid")

    tasks: list[_TaskModel]


def default_request(objects: Sequence[str]) -> str:
    """``"set the table with a X, a Y and an Z"`` for ``objects``."""
    named = [f"{'an' if o[:1].lower() in 'aeiou' else 'a'} {o}" for o in objects]
    listed = named[0] if len(named) == 1 else f"{', '.join(named[:-1])} and {named[-1]}"
    return f"set the table with {listed}"


def load_tasks(extra_files: Sequence[str | os.PathLike[str]] = ()) -> dict[int, Task]:
    """The packaged tasks, extended (or replaced by id) by ``extra_files``, sorted by id.

    Raises :class:`BadInput` naming the file and the field for a malformed file.
    """
    packaged = resources.files("llm_grop").joinpath("data/tasks.yaml")
    tasks = {t.id: t for t in _parse(packaged.read_text(encoding="utf-8"), "packaged tasks")}
    for path in extra_files:
        try:
            text = Path(path).read_text(encoding="utf-8")
        except OSError as exc:
            raise BadInput(f"tasks {path}: cannot read ({exc.strerror})") from None
        tasks.update({t.id: t for t in _parse(text, f"tasks {path}")})
    return dict(sorted(tasks.items()))


def get_task(n: int, tasks: Mapping[int, Task]) -> Task:
    """Task ``n`` of ``tasks``; raises :class:`BadInput` listing the valid ids."""
    if n not in tasks:
        valid = ", ".join(str(i) for i in sorted(tasks)) or "none"
        raise BadInput(f"task {n}: no such task; valid ids: {valid}")
    return tasks[n]


def _parse(text: str, where: str) -> list[Task]:
    model = load_yaml_model(text, where, _TasksModel, "tasks", "id")
    out: list[Task] = []
    seen: set[int] = set()
    for k, t in enumerate(model.tasks):
        if t.id in seen:
            raise BadInput(f"{where}: tasks[{k}].id: task {t.id} is defined twice")
        seen.add(t.id)
        out.append(Task(t.id, tuple(t.objects), tuple(t.tags),
                        t.request or default_request(t.objects)))
    return out
