"""The public Python API: the same operations the command line offers."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING

from llm_grop.arrangement.diners import seat_items, seat_table
from llm_grop.arrangement.pipeline import ArrangementResult, ArrangeOptions, arrange_items
from llm_grop.arrangement.stated import check_stated
from llm_grop.errors import BadInput
from llm_grop.execution import ExecutionPolicy
from llm_grop.language import understanding
from llm_grop.llm.base import LLM, BackendOptions, CallLog, SamplingParams
from llm_grop.llm.cache import LLMCache
from llm_grop.llm.registry import create_llm
from llm_grop.methods.registry import available_methods, get_method
from llm_grop.simulation.registry import DEFAULT_SIMULATOR, available_simulators
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import Request, items_from_names
from llm_grop.world.scene import Scene
from llm_grop.world.table import Table
from llm_grop.world.tasks import Task, get_task, load_tasks

if TYPE_CHECKING:
    from llm_grop.planning.utility import GropOptions
    from llm_grop.simulation.base import Simulator
    from llm_grop.world.plan import RunResult

__all__ = ["arrange", "available_methods", "available_simulators", "make_llm",
           "resolve_items", "run", "understand"]


def make_llm(llm: str | LLM = "embedded", options: BackendOptions | None = None,
             record: str | PathLike[str] | None = None,
             cache: str | PathLike[str] | None = None) -> CallLog:
    """A logged LLM: a backend by name (or an :class:`LLM` instance), recording to
    ``record``, answering seeded calls asked before from the LLM cache in directory
    ``cache`` (:mod:`llm_grop.llm.cache`; ``None``: no cache)."""
    backend = create_llm(llm, options) if isinstance(llm, str) else llm
    return CallLog(backend, Path(record) if record is not None else None,
                   cache=LLMCache(cache) if cache is not None else None)


def resolve_items(request: str | None, task: int | None, catalog: Catalog,
                  tasks: Mapping[int, Task] | None = None) -> tuple[str, tuple[Item, ...]]:
    """The request's text and its items, from ``request`` (read by the catalog matcher
    alone) or ``task``: an id of ``tasks`` (default: the paper's Table I)."""
    reading = understand(request, task=task, catalog=catalog, tasks=tasks, llm=None)
    return reading.text, reading.items


def understand(request: str | None = None, *, task: int | None = None,
               catalog: Catalog | None = None, tasks: Mapping[int, Task] | None = None,
               llm: str | LLM | CallLog | Callable[[], CallLog] | None = "embedded",
               llm_options: BackendOptions | None = None, seed: int = 0,
               params: SamplingParams | None = None,
               on_event: Callable[[str], None] | None = None, guess: bool = True,
               table: Table | None = None) -> Request:
    """What ``request`` (or the paper's Table I ``task``, an id of ``tasks``) asks for: its
    items, the relations it states, and how they were read.

    The catalog matcher reads the request alone when it accounts for every word; otherwise
    ``llm`` reads the whole request (:mod:`llm_grop.language.understanding`), and is made
    only then; ``llm=None`` refuses such a request with the words the matcher could not
    read. ``seed`` fixes that call's seed. ``guess=False`` refuses a reading with objects
    the request does not name. The stated relations are checked with clingo, and their
    distances against ``table`` when given.
    """
    catalog = catalog or Catalog.load()
    if task is not None:
        t = get_task(task, tasks if tasks is not None else load_tasks())
        return Request(request or t.request, tuple(items_from_names(
            t.objects, catalog, where=f"task {task}: objects")))
    if request is None:
        raise BadInput("request: give a request or a task number")
    log: CallLog | Callable[[], CallLog] | None
    if llm is None or isinstance(llm, CallLog) or callable(llm) and not isinstance(llm, LLM):
        log = llm
    else:
        backend = llm
        log = lambda: make_llm(backend, llm_options)  # noqa: E731
    reading = understanding.understand(request, catalog, log, seed, params, on_event, guess)
    check_stated(reading, table)
    return reading


def arrange(request: str | None = None, *, task: int | None = None,
            llm: str | LLM | CallLog = "embedded", llm_options: BackendOptions | None = None,
            table: Table | None = None, seed: int = 0, catalog: Catalog | None = None,
            catalog_files: Sequence[str | PathLike[str]] = (),
            options: ArrangeOptions | None = None, record: str | PathLike[str] | None = None,
            on_event: Callable[[str], None] | None = None, guess: bool = True
            ) -> ArrangementResult:
    """Arrange the objects of ``request`` (or of the paper's Table I ``task``) on ``table``.

    ``llm`` is a backend name (``"embedded"``, ``"openai"``, ``"replay"``), an
    :class:`LLM`, or a :class:`CallLog`. ``seed`` fixes every LLM call's seed and
    the sampler, so the same inputs give the same result. ``record`` appends each
    LLM call to a JSONL file that ``llm="replay"`` can read back. ``guess=False`` refuses
    a request whose reading needs the LLM to choose objects it does not name.
    """
    catalog = catalog or Catalog.load(catalog_files)
    options = options or ArrangeOptions()
    log = llm if isinstance(llm, CallLog) else make_llm(llm, llm_options, record)
    reading = understand(request, task=task, catalog=catalog, llm=log, seed=seed,
                         params=options.params, on_event=on_event, guess=guess,
                         table=table or Table())
    items = seat_items(reading.items, table or Table())
    top = seat_table(table or Table(), items)
    return arrange_items(reading, items, log, catalog, top, seed, options, on_event)


def run(request: str | None = None, *, task: int | None = None, method: str = "llm-grop",
        scene: Scene | str | PathLike[str] | None = None, chairs: int | None = None,
        table: Table | None = None, seed: int = 0, llm: str | LLM | CallLog = "embedded",
        llm_options: BackendOptions | None = None, catalog: Catalog | None = None,
        catalog_files: Sequence[str | PathLike[str]] = (),
        options: ArrangeOptions | None = None, record: str | PathLike[str] | None = None,
        simulator: str | Simulator = DEFAULT_SIMULATOR, planner: GropOptions | None = None,
        feasibility: str = "default",
        tasks: Mapping[int, Task] | None = None,
        on_event: Callable[[str], None] | None = None, guess: bool = True,
        execution: ExecutionPolicy | None = None) -> RunResult:
    """Arrange, plan and execute: the paper's whole pipeline in a simulated dining room.

    ``scene`` is a :class:`Scene`, a scene YAML file, or ``None`` for the packaged dining
    room. ``chairs`` chairs are sampled near the target table for this seed (``None``
    keeps the scene file's own chairs, or samples one if it lists none; ``chairs: []``
    in the file means no chairs); the robot senses
    them at planning time. ``table`` replaces the target table's top (same centre, yaw
    and height), e.g. ``Table.circle(1.2)`` for a round one; ``None`` keeps the scene's.
    ``method`` is one of :func:`available_methods` and ``simulator`` one of
    :func:`available_simulators` or a simulator object, such as a
    :class:`~llm_grop.simulation.mujoco.simulator.MujocoSimulator` with options (the plan
    is the same whichever executes it); ``feasibility`` names the planner's belief of how
    often actions succeed (``default``, or ``mujoco`` as fitted in 3D); ``tasks``
    replaces the paper's Table I for ``task``; ``guess=False`` refuses a request whose
    reading needs the LLM to choose objects; ``execution`` sets the executive's attempt
    counts and place tolerances (default: the authors' counts, 20 manipulation attempts
    for LLM-GROP and 10 for the baselines). The same seed gives the same run.
    """
    # Planning pulls in OMPL and scipy; import them only when a run needs them.
    from llm_grop.methods.base import EpisodeInput
    from llm_grop.methods.episode import run_episode
    from llm_grop.planning.feasibility import feasibility_profile
    from llm_grop.simulation.registry import create_simulator
    from llm_grop.simulation.scenario import prepare_episode
    from llm_grop.world.scene_file import load_scene, set_target_top

    catalog = catalog or Catalog.load(catalog_files)
    options = options or ArrangeOptions()
    chosen = get_method(method)
    sim = create_simulator(simulator) if isinstance(simulator, str) else simulator
    feasibility_profile(feasibility)  # an unknown profile is reported before any work
    base = scene if isinstance(scene, Scene) else load_scene(scene)
    if table is not None:
        base = set_target_top(base, table, keep_chairs=chairs is None)
    for k, source in enumerate(base.sources):
        kind = re.sub(r"\s+\d+$", "", source.object)
        if catalog.lookup(kind) is None:
            where = f"{scene}: " if scene is not None and not isinstance(scene, Scene) else ""
            raise BadInput(f"{where}sources[{k}] ({source.object!r}).object: unknown object; "
                           f"did you mean {', '.join(map(repr, catalog.suggest(kind))) or '?'}")
    if chairs is None and not (base.chairs or base.chairs_listed):
        chairs = 1
    made: list[CallLog] = [llm] if isinstance(llm, CallLog) else []

    def log() -> CallLog:
        if not made:
            made.append(make_llm(llm, llm_options, record))  # type: ignore[arg-type]
        return made[0]

    reading = understand(request, task=task, catalog=catalog, tasks=tasks, llm=log, seed=seed,
                         params=options.params, on_event=on_event, guess=guess,
                         table=base.target_top)
    items = seat_items(reading.items, base.target_top)  # a scene with seats: one setting each
    top = seat_table(base.target_top, items)  # too many diners: reported before any work
    check = getattr(sim, "check", None)
    if check is not None:
        check(base, items)
    episode = prepare_episode(base, items, seed, chairs=chairs)
    inp = EpisodeInput(reading.text, items, top, seed, catalog,
                       log() if chosen.uses_llm else None, options, on_event, reading)
    return run_episode(chosen, inp, episode, task=task, simulator=sim, planner=planner,
                       model=feasibility, policy=execution)
