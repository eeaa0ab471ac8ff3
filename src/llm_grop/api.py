"""The public Python API: the same operations the command line offers."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any

from llm_grop.arrangement.diners import seat_items, seat_table
from llm_grop.arrangement.pipeline import ArrangementResult, ArrangeOptions, arrange_items
from llm_grop.arrangement.stated import check_stated
from llm_grop.errors import BadInput
from llm_grop.execution import ExecutionPolicy
from llm_grop.execution.policy import BASELINE_MANIP_ATTEMPTS
from llm_grop.language import understanding
from llm_grop.llm.base import LLM, BackendOptions, CallLog, SamplingParams
from llm_grop.llm.cache import LLMCache
from llm_grop.llm.registry import create_llm
from llm_grop.methods.registry import available_methods, get_method
from llm_grop.simulation.registry import DEFAULT_SIMULATOR, available_simulators
from llm_grop.world.arrangement import Arrangement, Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import Request, items_from_names
from llm_grop.world.scene import Scene
from llm_grop.world.table import Table
from llm_grop.world.tasks import Task, get_task, load_tasks

if TYPE_CHECKING:
    from llm_grop.methods.base import EpisodeInput
    from llm_grop.methods.episode import PlannedEpisode
    from llm_grop.planning.utility import GropOptions
    from llm_grop.simulation.base import Simulator
    from llm_grop.world.plan import RunResult

__all__ = ["PlanResult", "arrange", "available_methods", "available_simulators", "execute",
           "make_llm", "plan", "plan_from_dict", "plan_to_dict", "resolve_items", "run",
           "understand"]


@dataclass(frozen=True)
class PlanResult:
    """A task-motion plan from :func:`plan`, not yet executed: the method's name, the
    paper's task (``None`` for a free request), what the method was given (request, items,
    table, seed), the arrangement and plan in their episode's scene, the planner's options
    and the attempts per pick and place the executive allows the method."""

    method: str
    task: int | None
    input: EpisodeInput
    planned: PlannedEpisode
    planner: GropOptions | None
    manip_attempts: int


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
            on_event: Callable[[str], None] | None = None, guess: bool = True,
            cache: str | PathLike[str] | None = None) -> ArrangementResult:
    """Arrange the objects of ``request`` (or of the paper's Table I ``task``) on ``table``.

    ``llm`` is a backend name (``"embedded"``, ``"openai"``, ``"replay"``), an
    :class:`LLM`, or a :class:`CallLog`. ``seed`` fixes every LLM call's seed and
    the sampler, so the same inputs give the same result. ``record`` appends each
    LLM call to a JSONL file that ``llm="replay"`` can read back. ``guess=False`` refuses
    a request whose reading needs the LLM to choose objects it does not name. ``cache``
    is the directory of an LLM answer cache (:func:`make_llm`): a seeded call asked
    before is answered from it (a :class:`CallLog` given as ``llm`` keeps its own).
    """
    catalog = catalog or Catalog.load(catalog_files)
    options = options or ArrangeOptions()
    log = llm if isinstance(llm, CallLog) else make_llm(llm, llm_options, record, cache)
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
        execution: ExecutionPolicy | None = None,
        cache: str | PathLike[str] | None = None) -> RunResult:
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
    for LLM-GROP and 10 for the baselines); ``cache`` is an LLM answer cache's directory
    (:func:`make_llm`). The same seed gives the same run: it is :func:`plan` followed by
    :func:`execute`.
    """
    from llm_grop.simulation.registry import create_simulator

    sim = create_simulator(simulator) if isinstance(simulator, str) else simulator
    planned = plan(request, task=task, method=method, scene=scene, chairs=chairs, table=table,
                   seed=seed, llm=llm, llm_options=llm_options, catalog=catalog,
                   catalog_files=catalog_files, options=options, record=record,
                   planner=planner, feasibility=feasibility, tasks=tasks, on_event=on_event,
                   guess=guess, check=getattr(sim, "check", None), cache=cache)
    return execute(planned, simulator=sim, execution=execution)


def plan(request: str | None = None, *, task: int | None = None,
         arrangement: Arrangement | None = None, method: str = "llm-grop",
         scene: Scene | str | PathLike[str] | None = None, chairs: int | None = None,
         table: Table | None = None, seed: int = 0, llm: str | LLM | CallLog = "embedded",
         llm_options: BackendOptions | None = None, catalog: Catalog | None = None,
         catalog_files: Sequence[str | PathLike[str]] = (),
         options: ArrangeOptions | None = None, record: str | PathLike[str] | None = None,
         planner: GropOptions | None = None, feasibility: str = "default",
         tasks: Mapping[int, Task] | None = None,
         on_event: Callable[[str], None] | None = None, guess: bool = True,
         check: Callable[[Scene, Sequence[Item]], None] | None = None,
         cache: str | PathLike[str] | None = None) -> PlanResult:
    """Arrange and plan, without executing: what :func:`run` does before the simulator
    starts, for a robot stack to execute (the arguments are :func:`run`'s).

    With ``arrangement`` (an :class:`Arrangement`, e.g. read with
    :func:`~llm_grop.world.serialize.arrangement_from_dict`) instead of a request, its
    placements are planned for as they are, on its table, and no LLM is asked; ``method``
    then only chooses how standing positions are picked. ``check(scene, items)`` may refuse
    the episode before any work (a simulator's own check). :func:`execute` runs the plan.
    """
    from llm_grop.methods.base import EpisodeInput, GivenArrangement
    from llm_grop.methods.episode import plan_episode
    from llm_grop.planning.feasibility import feasibility_profile
    from llm_grop.simulation.scenario import prepare_episode
    from llm_grop.world.scene_file import load_scene, set_target_top

    catalog = catalog or Catalog.load(catalog_files)
    options = options or ArrangeOptions()
    chosen = get_method(method)
    feasibility_profile(feasibility)  # an unknown profile is reported before any work
    base = scene if isinstance(scene, Scene) else load_scene(scene)
    if arrangement is not None:
        if request is not None or task is not None:
            raise BadInput("arrangement: give a request, a task or an arrangement, not both")
        table = arrangement.table
    if table is not None:
        base = set_target_top(base, table, keep_chairs=chairs is None)
    for k, source in enumerate(base.sources):
        kind = _NUMBERED.sub("", source.object)
        if catalog.lookup(kind) is None:
            where = f"{scene}: " if scene is not None and not isinstance(scene, Scene) else ""
            raise BadInput(f"{where}sources[{k}] ({source.object!r}).object: unknown object; "
                           f"did you mean {', '.join(map(repr, catalog.suggest(kind))) or '?'}")
    if chairs is None and not (base.chairs or base.chairs_listed):
        chairs = 1
    made: list[CallLog] = [llm] if isinstance(llm, CallLog) else []

    def log() -> CallLog:
        if not made:
            made.append(make_llm(llm, llm_options, record, cache))  # type: ignore[arg-type]
        return made[0]

    if arrangement is not None:
        reading = Request(arrangement.request, _given_items(arrangement, catalog))
        chosen = GivenArrangement(chosen, arrangement)
    else:
        reading = understand(request, task=task, catalog=catalog, tasks=tasks, llm=log,
                             seed=seed, params=options.params, on_event=on_event,
                             guess=guess, table=base.target_top)
    items = seat_items(reading.items, base.target_top)  # a scene with seats: one setting each
    top = seat_table(base.target_top, items)  # too many diners: reported before any work
    if top.diners and not base.diners:
        # The seats the settings were placed for are the scene's, so a 3D world draws a
        # placemat at each and the diner's camera sits at the first.
        base = replace(base, diners=top.diners)
    if check is not None:
        check(base, items)
    episode = prepare_episode(base, items, seed, chairs=chairs)
    inp = EpisodeInput(reading.text, items, top, seed, catalog,
                       log() if chosen.uses_llm else None, options, on_event, reading)
    planned = plan_episode(chosen, inp, episode, model=feasibility, planner=planner)
    return PlanResult(chosen.name, task, inp, planned, planner,
                      getattr(chosen, "manip_attempts", BASELINE_MANIP_ATTEMPTS))


def execute(planned: PlanResult, *, simulator: str | Simulator = DEFAULT_SIMULATOR,
            execution: ExecutionPolicy | None = None) -> RunResult:
    """Execute a plan from :func:`plan` on ``simulator`` (a name or a simulator object): the
    same run as :func:`run` with the same arguments and seed."""
    from llm_grop.methods.episode import execute_episode
    from llm_grop.simulation.registry import create_simulator

    sim = create_simulator(simulator) if isinstance(simulator, str) else simulator
    return execute_episode(planned.planned, planned.input, task=planned.task, simulator=sim,
                           method=planned.method, attempts=planned.manip_attempts,
                           planner=planned.planner, policy=execution)


#: A trailing instance number: "dinner fork 2" is of kind "dinner fork".
_NUMBERED = re.compile(r"\s+\d+$")


def _given_items(arrangement: Arrangement, catalog: Catalog) -> tuple[Item, ...]:
    """The items of a given arrangement, each of its placement's catalog kind."""
    origins = {name: (source, words) for name, source, words in arrangement.origins}
    items = []
    for k, p in enumerate(arrangement.placements):
        kind = p.kind if p.kind and p.kind != p.name else _NUMBERED.sub("", p.name)
        spec = catalog.resolve(kind, f"arrangement: objects[{k}].kind")
        source, words = origins.get(p.name, ("request", ""))
        items.append(Item(p.name, spec, p.diner, source, words))
    return tuple(items)


def plan_to_dict(planned: PlanResult) -> dict[str, Any]:
    """The plan JSON of ``planned`` (:mod:`llm_grop.world.plan_doc`): the steps a robot stack
    executes, in the contract's frames, at full precision."""
    from llm_grop.world.plan_doc import plan_json

    p = planned.planned
    return plan_json(method=planned.method, task=planned.task, seed=planned.input.seed,
                     request=planned.input.request, plan=p.plan, arrangement=p.arrangement,
                     scene=p.scene, planning_time_s=p.planning_time_s,
                     feasibility=p.feasibility,
                     manip_attempts=planned.manip_attempts).to_json()


def plan_from_dict(data: Mapping[str, Any], *, catalog: Catalog | None = None,
                   where: str = "plan") -> PlanResult:
    """A plan JSON read back (as :func:`plan_to_dict` wrote it), ready for :func:`execute`:
    executing it gives the same run as executing the plan it was written from."""
    from llm_grop.methods.base import EpisodeInput
    from llm_grop.methods.episode import PlannedEpisode
    from llm_grop.world.plan_doc import read_plan_json

    catalog = catalog or Catalog.load()
    doc, the_plan, arrangement, scene = read_plan_json(data, where)
    items = _given_items(arrangement, catalog)
    inp = EpisodeInput(doc.request, items, arrangement.table, doc.seed, catalog)
    planned = PlannedEpisode(arrangement, the_plan, scene, doc.planning_time_s,
                             doc.feasibility)
    return PlanResult(doc.method, doc.task, inp, planned, None, doc.manip_attempts)
