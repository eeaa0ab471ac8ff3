"""llm-grop: set a table the way people expect, from an underspecified request.

An implementation of LLM-GROP (Ding, Zhang, Paxton, Zhang, IROS 2023)::

    from llm_grop import arrange, run
    result = arrange("a dinner plate, a dinner fork and a dinner knife", seed=0)
    for p in result.arrangement.placements:
        print(p.name, p.x, p.y)
    episode = run(task=8, seed=0)
    print(episode.success, episode.execution.execution_time_s)

Every name below is importable from ``llm_grop``; each is loaded on first use, so
``import llm_grop`` stays cheap.
"""

from __future__ import annotations

import importlib
from importlib import metadata
from typing import TYPE_CHECKING, Any

from llm_grop import moved

# Old import paths of modules that moved (llm_grop.world.contract, ...) keep working.
moved.install()

if TYPE_CHECKING:
    from llm_grop.api import (
        PlanResult,
        arrange,
        available_methods,
        available_simulators,
        execute,
        learn,
        make_llm,
        plan,
        plan_from_dict,
        plan_to_dict,
        run,
        understand,
    )
    from llm_grop.arrangement.learning import Learned, Learning
    from llm_grop.arrangement.pipeline import ArrangementResult, ArrangeOptions
    from llm_grop.contract.run_json import run_to_dict
    from llm_grop.contract.serialize import arrangement_from_dict, arrangement_to_dict
    from llm_grop.errors import BadInput, Infeasible, LLMError, LLMGropError, LLMTransient
    from llm_grop.evaluation.rater import Rating, rate
    from llm_grop.files.jsonio import write_json
    from llm_grop.files.scene_file import load_scene
    from llm_grop.llm.base import LLM, BackendOptions, CallLog, SamplingParams
    from llm_grop.llm.registry import register_backend
    from llm_grop.methods.registry import register_method
    from llm_grop.planning.utility import GropOptions
    from llm_grop.render.room import draw_run
    from llm_grop.render.table import draw_arrangement
    from llm_grop.settings import RunSettings
    from llm_grop.simulation.registry import register_simulator
    from llm_grop.world.arrangement import Arrangement, Configuration, Item, Placement
    from llm_grop.world.catalog import Catalog, ObjectSpec
    from llm_grop.world.plan import RunResult
    from llm_grop.world.relation import Relation
    from llm_grop.world.request import Request
    from llm_grop.world.scene import Scene
    from llm_grop.world.table import Table

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    "arrange": "llm_grop.api",
    "available_methods": "llm_grop.api",
    "available_simulators": "llm_grop.api",
    "make_llm": "llm_grop.api",
    "run": "llm_grop.api",
    "plan": "llm_grop.api",
    "execute": "llm_grop.api",
    "PlanResult": "llm_grop.api",
    "plan_to_dict": "llm_grop.api",
    "plan_from_dict": "llm_grop.api",
    "understand": "llm_grop.api",
    "learn": "llm_grop.api",
    "Learned": "llm_grop.arrangement.learning",
    "Learning": "llm_grop.arrangement.learning",
    "RunSettings": "llm_grop.settings",
    "Request": "llm_grop.world.request",
    "ArrangeOptions": "llm_grop.arrangement.pipeline",
    "ArrangementResult": "llm_grop.arrangement.pipeline",
    "BadInput": "llm_grop.errors",
    "Infeasible": "llm_grop.errors",
    "LLMError": "llm_grop.errors",
    "LLMGropError": "llm_grop.errors",
    "LLMTransient": "llm_grop.errors",
    "Rating": "llm_grop.evaluation.rater",
    "rate": "llm_grop.evaluation.rater",
    "LLM": "llm_grop.llm.base",
    "BackendOptions": "llm_grop.llm.base",
    "CallLog": "llm_grop.llm.base",
    "SamplingParams": "llm_grop.llm.base",
    "register_backend": "llm_grop.llm.registry",
    "register_method": "llm_grop.methods.registry",
    "GropOptions": "llm_grop.planning.utility",
    "ExecutionPolicy": "llm_grop.execution.policy",
    "draw_run": "llm_grop.render.room",
    "draw_arrangement": "llm_grop.render.table",
    "register_simulator": "llm_grop.simulation.registry",
    "Arrangement": "llm_grop.world.arrangement",
    "Configuration": "llm_grop.world.arrangement",
    "Item": "llm_grop.world.arrangement",
    "Placement": "llm_grop.world.arrangement",
    "Catalog": "llm_grop.world.catalog",
    "ObjectSpec": "llm_grop.world.catalog",
    "RunResult": "llm_grop.world.plan",
    "Relation": "llm_grop.world.relation",
    "run_to_dict": "llm_grop.contract.run_json",
    "Scene": "llm_grop.world.scene",
    "load_scene": "llm_grop.files.scene_file",
    "arrangement_from_dict": "llm_grop.contract.serialize",
    "arrangement_to_dict": "llm_grop.contract.serialize",
    "write_json": "llm_grop.files.jsonio",
    "Table": "llm_grop.world.table",
}

__all__ = [
    "ArrangeOptions",
    "Arrangement",
    "ArrangementResult",
    "BackendOptions",
    "BadInput",
    "CallLog",
    "Catalog",
    "Configuration",
    "ExecutionPolicy",
    "GropOptions",
    "Infeasible",
    "Item",
    "LLM",
    "Learned",
    "Learning",
    "LLMError",
    "LLMGropError",
    "LLMTransient",
    "ObjectSpec",
    "Placement",
    "PlanResult",
    "Rating",
    "Relation",
    "Request",
    "RunResult",
    "RunSettings",
    "SamplingParams",
    "Scene",
    "Table",
    "arrange",
    "arrangement_from_dict",
    "execute",
    "learn",
    "plan",
    "plan_from_dict",
    "plan_to_dict",
    "arrangement_to_dict",
    "available_methods",
    "available_simulators",
    "draw_arrangement",
    "draw_run",
    "load_scene",
    "make_llm",
    "rate",
    "register_backend",
    "register_method",
    "register_simulator",
    "run",
    "run_to_dict",
    "understand",
    "write_json",
]

try:
    __version__ = metadata.version("llm-grop")
except metadata.PackageNotFoundError:  # run from a source tree that was never installed
    __version__ = "0+unknown"


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'llm_grop' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])
