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

import yaml
from pydantic import BaseModel, ConfigDict, Field, StrictInt, StringConstraints, ValidationError

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
    try:
        raw = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" line {mark.line + 1}" if mark is not None else ""
        raise BadInput(f"{where}{at}: not valid YAML") from None
    if not isinstance(raw, dict):
        raise BadInput(f"{where}: top level: expected a mapping with a 'tasks' list")
    try:
        model = _TasksModel.model_validate(raw)
    except ValidationError as exc:
        err = exc.errors()[0]
        raise BadInput(f"{where}: {_location(raw, err['loc'])}: {err['msg']}") from None
    out: list[Task] = []
    seen: set[int] = set()
    for k, t in enumerate(model.tasks):
        if t.id in seen:
            raise BadInput(f"{where}: tasks[{k}].id: task {t.id} is defined twice")
        seen.add(t.id)
        out.append(Task(t.id, tuple(t.objects), tuple(t.tags),
                        t.request or default_request(t.objects)))
    return out


def _location(raw: object, loc: tuple[int | str, ...]) -> str:
    """A readable field path such as ``tasks[2] (id 3).objects[0]``."""
    parts: list[str] = []
    node = raw
    for key in loc:
        if isinstance(key, int):
            label = f"[{key}]"
            if isinstance(node, list) and key < len(node):
                node = node[key]
                if isinstance(node, dict) and "id" in node and not parts[1:]:
                    label += f" (id {node['id']!r})"
            parts.append(label)
        else:
            parts.append(f".{key}" if parts else str(key))
            node = node.get(key) if isinstance(node, dict) else None
    return "".join(parts) or "top level"
