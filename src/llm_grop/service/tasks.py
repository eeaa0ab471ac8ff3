"""What a worker does for each kind of job: the public API called as the CLI calls it,
with the server's own LLM backends, and the answer as JSON and files (pictures, renders,
the video, and, where the server has the [viz] extra, the run's Rerun recording)."""

from __future__ import annotations

import json
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

from llm_grop.assembly import call_log
from llm_grop.errors import BadInput
from llm_grop.llm.base import LLM, CallLog
from llm_grop.llm.registry import create_llm
from llm_grop.service.config import ServiceConfig
from llm_grop.service.models import (
    ArrangeBody,
    PlanBody,
    PreferencesBody,
    RunBody,
    preferences_answer,
)
from llm_grop.settings import RunSettings
from llm_grop.world.table import Table

Files = dict[str, tuple[str, bytes]]
#: Most walls, tables, sources or chairs an inline scene may list.
MAX_SCENE_ITEMS = 100
PNG = "image/png"
#: A Rerun recording's media type (Rerun names none of its own).
RRD = "application/octet-stream"


class Backends:
    """A worker's LLM backends, each built once, on first use, and kept for its jobs."""

    def __init__(self, config: ServiceConfig) -> None:
        self.config = config
        self._made: dict[str, LLM] = {}

    def log(self, name: str | None) -> CallLog:
        """A fresh call log over the backend called ``name`` (``None``: the default)."""
        backend = self.config.backend(name)
        if backend.name not in self._made:
            options = backend.options
            if self.config.llm_threads is not None:
                options = replace(options, n_threads=self.config.llm_threads)
            self._made[backend.name] = create_llm(backend.name, options)
        return call_log(self._made[backend.name])

    def close(self) -> None:
        """Release every backend."""
        for llm in self._made.values():
            llm.close()
        self._made.clear()


def perform(kind: str, body: dict[str, Any], config: ServiceConfig, llms: Backends,
            on_event: Callable[[str], None]) -> tuple[dict[str, Any], Files]:
    """Do the job ``kind`` (``arrange``, ``plan``, ``run`` or ``learn``) for the ``body``:
    its result JSON and files. Raises the project's errors for bad input (422) and
    nothing feasible (409)."""
    if kind == "arrange":
        return _arrange(ArrangeBody.model_validate(body), config, llms, on_event)
    if kind == "learn":
        return _learn(PreferencesBody.model_validate(body), llms, on_event)
    if kind == "plan":
        return _plan(PlanBody.model_validate(body), config, llms, on_event)
    return _run(RunBody.model_validate(body), config, llms, on_event)


#: Body fields named as a setting that are no value of it: the server's backend by its
#: name, the table as an object, the scene and the example settings as documents and the
#: sensed chairs (the record's ``scene`` and ``examples`` are files and its ``chairs`` a
#: number to sample).
_APART = ("llm", "table", "scene", "chairs", "examples")


def _settings(body: ArrangeBody | PlanBody) -> RunSettings:
    """The settings record of a body's fields that the record holds (a JSON body names
    them as the record does; the LLM is the server's, chosen apart)."""
    return RunSettings.make({name: getattr(body, name) for name in type(body).model_fields
                             if name in RunSettings.model_fields and name not in _APART})


def _learned(body: ArrangeBody | PlanBody) -> dict[str, Any]:
    """The keyword giving the arrangement the preferences learned from the body's example
    settings, with the server's catalog (none: no keyword)."""
    from llm_grop.arrangement.options import ArrangeOptions
    from llm_grop.assembly import learned_options
    from llm_grop.world.catalog import Catalog

    if not body.examples:
        return {}
    return {"options": ArrangeOptions(**learned_options(body.examples, Catalog.load(),
                                                        "examples"))}


def check_plugin_options(body: ArrangeBody | PlanBody) -> None:
    """:class:`BadInput` for a body's method or simulator options that the plugin does not
    declare, of the wrong type, or naming a file: a client never chooses where the server
    reads or writes."""
    from llm_grop.methods.registry import get_method
    from llm_grop.simulation.registry import simulator_class

    if isinstance(body, PlanBody):
        _checked(get_method(body.method).Options, body.method_options,
                 f"method {body.method!r}", "method_options")
    if isinstance(body, RunBody):
        _checked(simulator_class(body.simulator).Options, body.sim_options,
                 f"simulator {body.simulator!r}", "sim_options")


def _checked(options: type, given: Mapping[str, Any], owner: str, param: str) -> None:
    from llm_grop.settings.declared import declared_options, path_options

    named = [k for k in given if k in path_options(options)]
    if named:
        raise BadInput("names a file on the server, which a client may not choose",
                       param=f"{param}.{named[0]}")
    declared_options(options, given, owner=owner, param=param)


def _table(body: ArrangeBody) -> Table:
    # Its diners are seated by the settings record's ``diners``, as for the command line.
    return body.table.table() if body.table is not None else Table()


def _png(draw: Callable[[Path], object], scratch: Path) -> bytes:
    with tempfile.TemporaryDirectory(prefix="picture-", dir=scratch) as tmp:
        path = Path(tmp) / "picture.png"
        draw(path)
        return path.read_bytes()


def _check_size(count: int, config: ServiceConfig) -> None:
    if count > config.limits.objects:
        raise BadInput(f"request: {count} objects; this server sets at most "
                       f"{config.limits.objects}")


def _arrange(body: ArrangeBody, config: ServiceConfig, llms: Backends,
             on_event: Callable[[str], None]) -> tuple[dict[str, Any], Files]:
    from llm_grop.api import arrange
    from llm_grop.contract.serialize import arrangement_to_dict

    result = arrange(body.request, _settings(body), llm=llms.log(body.llm),
                     table=_table(body), on_event=on_event, **_learned(body))
    _check_size(len(result.arrangement.placements), config)
    return ({"arrangement": arrangement_to_dict(result.arrangement)},
            _table_pictures(result.arrangement, config.scratch))


def _learn(body: PreferencesBody, llms: Backends, on_event: Callable[[str], None]
           ) -> tuple[dict[str, Any], Files]:
    """The preferences the body's examples teach, generalised by the server's LLM."""
    from llm_grop.api import learn
    from llm_grop.world.catalog import Catalog

    on_event("learning from the examples, then asking the LLM for rules")
    learned = learn(body.examples, catalog=Catalog.load(), generalise=True,
                    llm=llms.log(body.llm), seed=body.seed)
    return {"preferences": preferences_answer(learned).model_dump(mode="json")}, {}


def _table_pictures(arrangement: Any, scratch: Path) -> Files:
    """The arrangement's picture, and one for a phone's screen."""
    from llm_grop.render.table import PHONE_SIZE_IN, draw_arrangement

    return {"table.png": (PNG, _png(lambda p: draw_arrangement(arrangement, p), scratch)),
            "table_phone.png": (PNG, _png(lambda p: draw_arrangement(
                arrangement, p, size_in=PHONE_SIZE_IN), scratch))}


def _scene(body: PlanBody) -> Any:
    """The room the body describes: its inline scene (or the packaged one) with the sensed
    chairs and the robot's pose it gives; ``None`` for the packaged room as it is."""
    from llm_grop.files.scene_file import load_scene, parse_scene, scene_to_dict

    if body.scene is None and body.chairs is None and body.robot is None:
        return None
    data = dict(body.scene) if body.scene is not None else scene_to_dict(load_scene())
    for key in ("walls", "tables", "sources", "chairs", "source_tables"):
        listed = data.get(key)
        if isinstance(listed, list) and len(listed) > MAX_SCENE_ITEMS:
            raise BadInput(f"scene.{key}: {len(listed)} entries; this server takes at most "
                           f"{MAX_SCENE_ITEMS}")
    if body.chairs is not None:
        data["chairs"] = [c.model_dump(mode="json") for c in body.chairs]
    if body.robot is not None:
        data["robot"] = {**(data.get("robot") or {}), "start": list(body.robot)}
    return parse_scene(json.dumps(data), "scene")


def _planned(body: PlanBody, config: ServiceConfig, llms: Backends,
             on_event: Callable[[str], None], check: Callable[..., None] | None = None
             ) -> Any:
    from llm_grop.api import plan
    from llm_grop.contract.serialize import arrangement_from_dict

    if sum(x is not None for x in (body.request, body.task, body.arrangement)) != 1:
        raise BadInput("request: give one of request, task or arrangement")
    arrangement = arrangement_from_dict(body.arrangement, "arrangement") \
        if body.arrangement is not None else None
    if arrangement is not None:
        _check_size(len(arrangement.placements), config)
    check_plugin_options(body)
    settings = _settings(body)
    planned = plan(body.request, settings, arrangement=arrangement, scene=_scene(body),
                   table=body.table.table() if body.table is not None else None,
                   llm=llms.log(body.llm), on_event=on_event, check=check, **_learned(body))
    _check_size(len(planned.input.items), config)
    return planned


def _plan(body: PlanBody, config: ServiceConfig, llms: Backends,
          on_event: Callable[[str], None]) -> tuple[dict[str, Any], Files]:
    from llm_grop.api import plan_to_dict
    from llm_grop.render.room import draw_plan

    planned = _planned(body, config, llms, on_event)
    p = planned.planned
    arranged = replace(p.arrangement, placements=p.plan.configuration)
    files = _table_pictures(arranged, config.scratch) | {
        "room.png": (PNG, _png(lambda f: draw_plan(p.scene, p.plan, arranged, f),
                               config.scratch))}
    return {"plan": plan_to_dict(planned)}, files


def _run(body: RunBody, config: ServiceConfig, llms: Backends,
         on_event: Callable[[str], None]) -> tuple[dict[str, Any], Files]:
    from llm_grop.api import execute
    from llm_grop.contract.run_json import run_to_dict
    from llm_grop.render.room import draw_run
    from llm_grop.simulation.registry import create_simulator, simulator_class

    renders = simulator_class(body.simulator).supports_pictures
    with tempfile.TemporaryDirectory(prefix="run-", dir=config.scratch) as tmp:
        video = Path(tmp) / "episode.mp4"
        films = body.video and simulator_class(body.simulator).supports_video
        sim = create_simulator(body.simulator, body.sim_options | (
            {"video_path": str(video)} if films else {}))
        if renders:
            sim.check_rendering()
        planned = _planned(body, config, llms, on_event, check=sim.check)
        # Every run is recorded where the server can (the extra is optional); the file is
        # the server's, never a client's path.
        recording = Path(tmp) / "episode.rrd" if _records() else None
        result = execute(planned, simulator=sim,
                         rerun=str(recording) if recording is not None else None)
        files: Files = _table_pictures(result.final, config.scratch) | {
            "room.png": (PNG, _png(lambda f: draw_run(result, f), config.scratch))}
        if renders:
            from llm_grop.render.raster import save_rgb_png

            for view in ("table", "room"):
                image = sim.picture(view)
                files[f"render_{view}.png"] = (PNG, _png(lambda f, i=image: save_rgb_png(i, f),
                                                         config.scratch))
        if films and video.exists():
            files["episode.mp4"] = ("video/mp4", video.read_bytes())
        if recording is not None and recording.exists():
            files["episode.rrd"] = (RRD, recording.read_bytes())
    return {"run": run_to_dict(result)}, files


def _records() -> bool:
    """Whether this server writes Rerun recordings (the [viz] extra is installed)."""
    import importlib.util

    return importlib.util.find_spec("rerun") is not None
