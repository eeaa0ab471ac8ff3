"""The public Python API: the same operations the command line offers."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from os import PathLike
from typing import TYPE_CHECKING, Any

from llm_grop.arrangement.diners import seat_items, seat_table
from llm_grop.arrangement.pipeline import (  # noqa: F401 - ArrangeOptions: public name
    ArrangementResult,
    ArrangeOptions,
    arrange_items,
)
from llm_grop.arrangement.stated import check_stated
from llm_grop.assembly import (
    RunInputs,
    arrange_options,
    call_log,
    check_recordings,
    execution_policy,
    make_simulator,
    named_simulator,
    open_recordings,
    planner_options,
    resolve_feasibility,
    resolve_llm,
    sampling,
    seat_diners,
    seat_scene_diners,
    settle,
    with_robot_settings,
)
from llm_grop.errors import BadInput
from llm_grop.language import understanding
from llm_grop.llm.base import LLM, BackendOptions, CallLog
from llm_grop.llm.registry import create_llm
from llm_grop.methods.registry import available_methods, get_method
from llm_grop.settings import DEFAULTS, RunSettings
from llm_grop.simulation.registry import available_simulators
from llm_grop.world.arrangement import Arrangement, Item
from llm_grop.world.catalog import Catalog, instance_kind
from llm_grop.world.request import Request, items_from_names
from llm_grop.world.scene import Scene
from llm_grop.world.table import Table
from llm_grop.world.tasks import Task, get_task, load_tasks

if TYPE_CHECKING:
    from llm_grop.arrangement.learning import Learning
    from llm_grop.methods.base import EpisodeInput
    from llm_grop.methods.episode import PlannedEpisode
    from llm_grop.planning.utility import GropOptions
    from llm_grop.simulation.base import Simulator
    from llm_grop.world.plan import RunResult

__all__ = ["PlanResult", "RunSettings", "arrange", "available_methods",
           "available_simulators", "execute", "learn", "make_llm", "plan", "plan_from_dict",
           "plan_to_dict", "resolve_items", "run", "understand"]


@dataclass(frozen=True)
class PlanResult:
    """A task-motion plan from :func:`plan`, not yet executed: the method's name, the
    paper's task (``None`` for a free request), what the method was given (request, items,
    table, seed), the arrangement and plan in their episode's scene, the planner's options,
    the attempts per pick and place the executive allows the method, and the settings it
    was planned with (:func:`execute`'s default)."""

    method: str
    task: int | None
    input: EpisodeInput
    planned: PlannedEpisode
    planner: GropOptions | None
    manip_attempts: int
    settings: RunSettings = DEFAULTS


def make_llm(llm: str | LLM = "embedded", options: BackendOptions | None = None,
             record: str | PathLike[str] | None = None,
             cache: str | PathLike[str] | None = None) -> CallLog:
    """A logged LLM: a backend by name (or an :class:`LLM` instance), recording to
    ``record``, answering seeded calls asked before from the LLM cache in directory
    ``cache`` (:mod:`llm_grop.llm.cache`; ``None``: no cache)."""
    backend = create_llm(llm, options) if isinstance(llm, str) else llm
    return call_log(backend, record=record, cache=cache,
                    max_answer_bytes=(options or BackendOptions()).max_answer_bytes)


def resolve_items(request: str | None, task: int | None, catalog: Catalog,
                  tasks: Mapping[int, Task] | None = None) -> tuple[str, tuple[Item, ...]]:
    """The request's text and its items, from ``request`` (read by the catalog matcher
    alone) or ``task``: an id of ``tasks`` (default: the paper's Table I)."""
    reading = _understand(request, DEFAULTS.with_values(task=task), catalog, tasks, None,
                          None, None)
    return reading.text, reading.items


#: :func:`understand`'s ``llm`` when none is given: the backend the settings name.
_SETTINGS_LLM: Any = object()


def understand(request: str | None = None, settings: RunSettings | None = None, *,
               llm: str | LLM | CallLog | Callable[[], CallLog] | None = _SETTINGS_LLM,
               catalog: Catalog | None = None, table: Table | None = None,
               on_event: Callable[[str], None] | None = None, **overrides: Any) -> Request:
    """What ``request`` (or the paper's Table I task ``task=N``) asks for: its items, the
    relations it states, and how they were read.

    The catalog matcher reads the request alone when it accounts for every word; otherwise
    an LLM reads the whole request (:mod:`llm_grop.language.understanding`): ``llm`` (an
    :class:`LLM`, a :class:`CallLog` or a function that makes one) or else the backend
    the settings name (a name given as ``llm`` is that setting), made only then;
    ``llm=None`` refuses such a request with the words the matcher could not read. ``settings`` and
    ``overrides`` are :func:`plan`'s: ``seed`` fixes the LLM call's seed, ``guess=False``
    refuses a reading with objects the request does not name, ``tasks`` replaces the
    paper's Table I. The stated relations are checked with clingo, and their distances
    against ``table`` when given.
    """
    refuse = llm is None
    job = RunInputs.of(settings, None if refuse or llm is _SETTINGS_LLM else llm, None, overrides)
    log: CallLog | Callable[[], CallLog] | None = None
    if not refuse:
        log = job.llm if isinstance(job.llm, CallLog) or callable(job.llm) and \
            not isinstance(job.llm, LLM) else job.log
    return _understand(request, job.settings, catalog, job.tasks, log, on_event, table)


def _understand(request: str | None, s: RunSettings, catalog: Catalog | None,
                tasks: Mapping[int, Task] | None,
                log: CallLog | Callable[[], CallLog] | None,
                on_event: Callable[[str], None] | None, table: Table | None) -> Request:
    """:func:`understand` with its settings made."""
    catalog = catalog or Catalog.load(s.catalog_files)
    if s.task is not None:
        t = get_task(s.task, tasks if tasks is not None else load_tasks(s.task_files))
        return Request(request or t.request, tuple(items_from_names(
            t.objects, catalog, where=f"task {s.task}: objects")))
    if request is None:
        raise BadInput("give a request or a task number", param="request")
    reading = understanding.understand(request, catalog, log, s.seed, sampling(s), on_event,
                                       s.guess)
    check_stated(reading, table)
    return reading


def arrange(request: str | None = None, settings: RunSettings | None = None, *,
            llm: LLM | CallLog | None = None, table: Table | None = None,
            catalog: Catalog | None = None, record: str | PathLike[str] | None = None,
            on_event: Callable[[str], None] | None = None, **overrides: Any
            ) -> ArrangementResult:
    """Arrange the objects of ``request`` (or of the paper's Table I task ``task=N``) on
    ``table`` (default: the record's, else a 0.9 x 0.6 m top).

    ``settings`` is the run's :class:`~llm_grop.settings.RunSettings` (default: its
    defaults); ``overrides`` change its fields by name (``seed=3``, ``m=10``,
    ``llm="openai"``), or give a component record whole (``options=ArrangeOptions(...)``,
    ``llm_options=BackendOptions(...)``). ``llm`` is an :class:`LLM` or a
    :class:`CallLog` to use instead of the record's backend (a name is the ``llm``
    setting). ``seed`` fixes every LLM call's seed and the sampler, so the same inputs
    give the same result. ``record`` appends each LLM call to a JSONL file that
    ``llm="replay"`` can read back. ``guess=False`` refuses a request whose reading needs
    the LLM to choose objects it does not name. The ``cache`` setting is the directory of
    an LLM answer cache: a seeded call asked before is answered from it (a
    :class:`CallLog` given as ``llm`` keeps its own).
    """
    if table is not None:
        overrides["table"] = table
    job = RunInputs.of(settings, llm, None, overrides | {"record": record})
    s = job.settings
    catalog = catalog or Catalog.load(s.catalog_files)
    options = arrange_options(s, job.bases.arrange, catalog)
    top = seat_diners(job.table or Table(), s)
    log = job.log()
    reading = _understand(request, s, catalog, job.tasks, log, on_event, top)
    items = seat_items(reading.items, top)
    seated = seat_table(top, items)
    return arrange_items(reading, items, log, catalog, seated, s.seed, options, on_event)


def run(request: str | None = None, settings: RunSettings | None = None, *,
        llm: LLM | CallLog | None = None, simulator: Simulator | None = None,
        scene: Scene | None = None, catalog: Catalog | None = None,
        on_event: Callable[[str], None] | None = None, **overrides: Any) -> RunResult:
    """Arrange, plan and execute: the paper's whole pipeline in a simulated dining room.

    The run is :func:`plan` followed by :func:`execute`, with the same ``settings`` (a
    :class:`~llm_grop.settings.RunSettings`, default its defaults) and ``overrides`` (its
    fields by name, e.g. ``task=8``, ``method="grop"``, ``chairs=4``, ``seed=3``,
    ``simulator="mujoco"``, ``nav_attempts=5``; see :func:`plan`). ``simulator`` is a
    simulator object to execute on instead of the record's (such as a
    :class:`~llm_grop.simulation.mujoco.simulator.MujocoSimulator` recording a video; the
    plan is the same whichever executes it). The same settings give the same run.
    """
    simulator, overrides = named_simulator(simulator, overrides)
    execution = overrides.pop("execution", None)
    job = RunInputs.of(settings, llm, scene, overrides)
    check_recordings(job.settings)  # before any work
    sim = simulator if simulator is not None else make_simulator(job.settings)
    job = replace(job, settings=resolve_feasibility(job.settings, sim))
    planned = _plan(request, job, catalog, on_event, sim.check)
    return execute(planned, simulator=sim, execution=execution)


def plan(request: str | None = None, settings: RunSettings | None = None, *,
         arrangement: Arrangement | None = None, llm: LLM | CallLog | None = None,
         scene: Scene | None = None, catalog: Catalog | None = None,
         on_event: Callable[[str], None] | None = None,
         check: Callable[[Scene, Sequence[Item]], None] | None = None,
         **overrides: Any) -> PlanResult:
    """Arrange and plan, without executing: what :func:`run` does before the simulator
    starts, for a robot stack to execute.

    ``settings`` is the run's :class:`~llm_grop.settings.RunSettings` and ``overrides``
    change its fields by name: ``task`` (the paper's Table I task instead of a request),
    ``method`` (one of :func:`available_methods`), ``scene`` (a scene YAML file; or a
    :class:`Scene` given as ``scene``), ``chairs`` (sampled near the target table for
    this seed; ``None`` keeps the scene file's own, or samples one if it lists none),
    ``table`` (replaces the target table's top: ``"1.2x0.8"``, ``"round:1.2"`` or a
    :class:`Table`), ``seed``, ``feasibility`` (the planner's belief: ``default``, or
    ``mujoco`` as fitted in 3D), ``weight`` and ``fidelity_weight``, the LLM's fields
    (``llm``, ``model``, ``temperature``, ...), ``guess``, ``cache``. Component records
    may be given whole: ``options`` (:class:`ArrangeOptions`), ``planner``
    (:class:`~llm_grop.planning.utility.GropOptions`), ``llm_options``
    (:class:`BackendOptions`); ``tasks`` replaces the paper's Table I and ``record``
    appends each LLM call to a JSONL file.

    With ``arrangement`` (an :class:`Arrangement`, e.g. read with
    :func:`~llm_grop.contract.serialize.arrangement_from_dict`) instead of a request, its
    placements are planned for as they are, on its table, and no LLM is asked; ``method``
    then only chooses how standing positions are picked. ``check(scene, items)`` may refuse
    the episode before any work (a simulator's own check). :func:`execute` runs the plan.
    """
    overrides.pop("execution", None)  # the executive's: execute() takes it
    job = RunInputs.of(settings, llm, scene, overrides)
    return _plan(request, job, catalog, on_event, check, arrangement)


def _plan(request: str | None, job: RunInputs, catalog: Catalog | None,
          on_event: Callable[[str], None] | None,
          check: Callable[[Scene, Sequence[Item]], None] | None,
          arrangement: Arrangement | None = None) -> PlanResult:
    """:func:`plan` of ``job``."""
    from llm_grop.files.scene_file import load_scene, set_target_top
    from llm_grop.methods.base import EpisodeInput, GivenArrangement
    from llm_grop.methods.episode import plan_episode
    from llm_grop.planning.feasibility import feasibility_profile
    from llm_grop.simulation.scenario import prepare_episode

    s = resolve_feasibility(job.settings)
    catalog = catalog or Catalog.load(s.catalog_files)
    tasks = job.tasks if job.tasks is not None or not s.task_files \
        else load_tasks(s.task_files)
    options = arrange_options(s, job.bases.arrange, catalog)
    chosen = get_method(s.method, dict(s.method_options))
    feasibility_profile(s.feasibility)  # an unknown profile is reported before any work
    planner = planner_options(s, job.bases.planner)
    base = job.scene if job.scene is not None else load_scene(s.scene)
    table, chairs = job.table, s.chairs
    if arrangement is not None:
        if request is not None or s.task is not None:
            raise BadInput("give a request, a task or an arrangement, not both",
                           param="arrangement")
        table = arrangement.table
    if table is not None:
        base = set_target_top(base, table, keep_chairs=chairs is None)
    base = seat_scene_diners(base, s)
    base = with_robot_settings(base, s)
    for k, source in enumerate(base.sources):
        kind = instance_kind(source.object)
        if catalog.lookup(kind) is None:
            where = f"{s.scene}: " if s.scene is not None and job.scene is None else ""
            raise BadInput(f"{where}sources[{k}] ({source.object!r}).object: unknown object; "
                           f"did you mean {', '.join(map(repr, catalog.suggest(kind))) or '?'}")
    if chairs is None and not (base.chairs or base.chairs_listed):
        chairs = 1
    made: list[CallLog] = []

    def log() -> CallLog:
        if not made:
            made.append(job.log())
        return made[0]

    if arrangement is not None:
        reading = Request(arrangement.request, _given_items(arrangement, catalog))
        chosen = GivenArrangement(chosen, arrangement)  # type: ignore[assignment]
    else:
        reading = _understand(request, s, catalog, tasks, log, on_event, base.target_top)
    items = seat_items(reading.items, base.target_top)  # a scene with seats: one setting each
    top = seat_table(base.target_top, items)  # too many diners: reported before any work
    if top.diners and not base.diners:
        # The seats the settings were placed for are the scene's, so a 3D world draws a
        # placemat at each and the diner's camera sits at the first.
        base = replace(base, diners=top.diners)
    if check is not None:
        check(base, items)
    episode = prepare_episode(base, items, s.seed, chairs=chairs)
    inp = EpisodeInput(reading.text, items, top, s.seed, catalog,
                       log() if chosen.arrangement.uses_llm else None, options, on_event,
                       reading)
    planned = plan_episode(chosen, inp, episode, model=s.feasibility, planner=planner)
    return PlanResult(chosen.name, s.task, inp, planned, planner, chosen.manip_attempts, s)


def execute(planned: PlanResult, settings: RunSettings | None = None, *,
            simulator: Simulator | None = None, **overrides: Any) -> RunResult:
    """Execute a plan from :func:`plan` on the simulator its settings name (or on the
    simulator object ``simulator``): the same run as :func:`run` with the same settings.

    ``settings`` defaults to the plan's own; ``overrides`` change its fields by name
    (``simulator="mujoco"``, ``nav_attempts=5``, ``rerun="run.rrd"`` to record the
    episode), or give the executive's policy whole (``execution=ExecutionPolicy(...)``,
    for its place tolerances).
    """
    from llm_grop.methods.episode import execute_episode

    simulator, overrides = named_simulator(simulator, overrides)
    s, bases = settle(settings or planned.settings, overrides)
    sim = simulator if simulator is not None else make_simulator(s)
    episode = open_recordings(s)
    try:
        return execute_episode(planned.planned, planned.input, task=planned.task,
                               simulator=sim, method=planned.method,
                               attempts=planned.manip_attempts, planner=planned.planner,
                               policy=execution_policy(s, bases.execution), observer=episode)
    finally:
        if episode is not None:
            episode.close()


def _given_items(arrangement: Arrangement, catalog: Catalog) -> tuple[Item, ...]:
    """The items of a given arrangement, each of its placement's catalog kind."""
    origins = {name: (source, words) for name, source, words in arrangement.origins}
    items = []
    for k, p in enumerate(arrangement.placements):
        kind = p.kind if p.kind and p.kind != p.name else instance_kind(p.name)
        spec = catalog.resolve(kind, f"arrangement: objects[{k}].kind")
        source, words = origins.get(p.name, ("request", ""))
        items.append(Item(p.name, spec, p.diner, source, words))
    return tuple(items)


def learn(examples: Sequence[str | PathLike[str] | Mapping[str, Any]],
          settings: RunSettings | None = None, *, catalog: Catalog | None = None,
          generalise: bool = False, llm: str | LLM | CallLog | None = None,
          **overrides: Any
          ) -> Learning:
    """A person's way of setting the table, learned from ``examples``: each an arrangement
    or run JSON file, or such a document parsed (a run's ``final`` is read). The result's
    sentences are preferences (write
    :meth:`~llm_grop.arrangement.learning.Learning.preference_file` to a file for
    ``preferences_file``); see :mod:`llm_grop.arrangement.learning`. With several
    examples, one that is not a table setting is a warning; :class:`BadInput` when none is.

    With ``generalise``, the run's LLM (``llm``, else the record's ``llm`` setting, with
    ``overrides`` as :func:`arrange` takes them) is asked for rules for the catalog's
    objects the examples do not show (:mod:`llm_grop.arrangement.generalising`, seed
    ``seed``). When ``--llm auto`` finds no capable model (it would fall back to the
    bundled SmolLM2-135M), only the exact sentences are learned, with one warning.
    """
    from llm_grop.arrangement.generalising import generalise as with_rules
    from llm_grop.arrangement.learning import learn as learn_examples

    job = RunInputs.of(settings, llm, None, overrides)
    s = job.settings
    catalog = catalog or Catalog.load(s.catalog_files)
    learned = learn_examples(examples, catalog)
    if not generalise:
        return learned
    if job.llm is None:
        s, choice = resolve_llm(s)
        if choice is not None and choice.weak:
            return replace(learned, warnings=learned.warnings + (
                "no capable model to generalise with: only the exact sentences are "
                "learned; start Ollama, llama.cpp's llama-server or vLLM, or pass "
                f"--base-url URL ({choice.why})",))
        job = replace(job, settings=s)
    return with_rules(learned, job.log(), catalog, s.seed, sampling(s))


def plan_to_dict(planned: PlanResult) -> dict[str, Any]:
    """The plan JSON of ``planned`` (:mod:`llm_grop.contract.plan_doc`): the steps a robot stack
    executes, in the contract's frames, at full precision."""
    from llm_grop.contract.plan_doc import plan_json

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
    from llm_grop.contract.plan_doc import read_plan_json
    from llm_grop.methods.base import EpisodeInput
    from llm_grop.methods.episode import PlannedEpisode

    catalog = catalog or Catalog.load()
    doc, the_plan, arrangement, scene = read_plan_json(data, where)
    items = _given_items(arrangement, catalog)
    inp = EpisodeInput(doc.request, items, arrangement.table, doc.seed, catalog)
    planned = PlannedEpisode(arrangement, the_plan, scene, doc.planning_time_s,
                             doc.feasibility)
    return PlanResult(doc.method, doc.task, inp, planned, None, doc.manip_attempts)
