"""What a :class:`~llm_grop.settings.RunSettings` record builds: the arrangement's, the
planner's, the LLM backend's and the executive's option records, the simulator and the
LLM's call log. Every front door (the API, the bench's trials, the service) builds them
here, so one record means one run wherever it comes from.

The component records (:class:`~llm_grop.arrangement.pipeline.ArrangeOptions`,
:class:`~llm_grop.planning.utility.GropOptions`, :class:`~llm_grop.llm.base.BackendOptions`,
:class:`~llm_grop.execution.ExecutionPolicy`) hold more than the record: advanced
settings (a stated relation's tolerance, the planner's standoffs, the executive's place
tolerances) that a caller of the Python API may give as such a record, its ``base``.
What the settings record holds always comes from the record.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from dataclasses import fields as dataclass_fields
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any

from llm_grop.arrangement.pipeline import ArrangeOptions
from llm_grop.execution import ExecutionPolicy
from llm_grop.llm.base import LLM, BackendOptions, BaseLLM, CallLog, SamplingParams
from llm_grop.llm.cache import LLMCache
from llm_grop.llm.registry import BACKENDS, create_llm
from llm_grop.planning.utility import GropOptions
from llm_grop.settings import DEFAULTS, RunSettings
from llm_grop.world.catalog import Catalog
from llm_grop.world.scene import Scene
from llm_grop.world.table import Table
from llm_grop.world.tasks import Task

if TYPE_CHECKING:
    from llm_grop.llm.auto import AutoChoice
    from llm_grop.recording.episode import Episode
    from llm_grop.simulation.base import Simulator

log = logging.getLogger(__name__)

#: The ``llm`` setting that picks a backend by what the machine offers.
AUTO = "auto"


@dataclass(frozen=True)
class Bases:
    """Component records a caller gave whole (``None``: the defaults), whose fields the
    settings record does not hold."""

    arrange: ArrangeOptions | None = None
    planner: GropOptions | None = None
    backend: BackendOptions | None = None
    execution: ExecutionPolicy | None = None


#: The component record a caller may give as a keyword, and the settings each field of
#: it sets (``None``: the record's own, kept as the base's).
_LIFTED: dict[str, tuple[type, dict[str, str]]] = {
    "options": (ArrangeOptions, {"m": "m", "max_attempts": "attempts", "notes": "notes",
                                 "preferences": "preferences"}),
    "planner": (GropOptions, {"w": "weight", "fidelity_w_s_per_cm": "fidelity_weight"}),
    "llm_options": (BackendOptions, {"model": "model", "base_url": "base_url",
                                     "timeout_s": "timeout_s", "max_retries": "retries",
                                     "max_answer_bytes": "max_answer_bytes",
                                     "replay_path": "replay"}),
    "execution": (ExecutionPolicy, {"nav_attempts": "nav_attempts",
                                    "manip_attempts": "manip_attempts"}),
}
#: The component record's keyword -> the field of :class:`Bases` it fills.
_BASE_FIELD = {"options": "arrange", "planner": "planner", "llm_options": "backend",
               "execution": "execution"}
#: Sampling settings: the :class:`SamplingParams` fields the settings record holds, by the
#: same names (the seed is each call's own).
_SAMPLING = tuple(f.name for f in dataclass_fields(SamplingParams) if f.name != "seed")


def settle(settings: RunSettings | None, given: dict[str, Any]) -> tuple[RunSettings, Bases]:
    """The record ``settings`` (``None``: the defaults) with ``given`` on top: fields of
    the record by name, or a component record whole (``options``, ``planner``,
    ``llm_options``, ``execution``), whose fields the record holds are lifted into it and
    whose others are kept as :class:`Bases`. A field given by name wins over a component
    record's."""
    base = settings or DEFAULTS
    changes: dict[str, Any] = {}
    bases: dict[str, Any] = {}
    for keyword in [k for k in given if k in _LIFTED]:
        record = given.pop(keyword)
        if record is None:
            continue
        kind, lifted = _LIFTED[keyword]
        if not isinstance(record, kind):
            from llm_grop.errors import BadInput

            raise BadInput(f"expected a {kind.__name__}, got {type(record).__name__}",
                           param=keyword)
        default = kind()
        for attr, name in lifted.items():
            value = getattr(record, attr)
            if value != getattr(default, attr):
                changes[name] = value
        if keyword == "options":
            changes |= _from_arrange_options(record)
        bases[_BASE_FIELD[keyword]] = record
    return base.with_values(**(changes | given)), Bases(**bases)


def _from_arrange_options(options: ArrangeOptions) -> dict[str, Any]:
    """The settings an :class:`ArrangeOptions` holds besides its lifted fields: its
    sampling and whether it leaves the examples out."""
    default = SamplingParams()
    out = {name: getattr(options.params, name) for name in _SAMPLING
           if getattr(options.params, name) != getattr(default, name)}
    if options.examples == "":
        out["zero_shot"] = True
    return out


def arrange_options(s: RunSettings, base: ArrangeOptions | None = None,
                    catalog: Catalog | None = None) -> ArrangeOptions:
    """The arrangement's options the record ``s`` sets, on ``base``'s others; the
    preferences file is read here, and the example settings learned from with ``catalog``
    (default: the record's) (a bad one is :class:`BadInput` naming it)."""
    from llm_grop.arrangement.preferences import load_preference_file

    base = base or ArrangeOptions()
    pool = load_preference_file(s.preferences_file) if s.preferences_file is not None \
        else base.preference_pool
    examples = "" if s.zero_shot else (base.examples if base.examples != "" else None)
    return replace(base, m=s.m, max_attempts=s.attempts, examples=examples, notes=s.notes,
                   params=sampling(s), preferences=s.preferences, preference_pool=pool,
                   revisions=s.revisions, **_learned(s, catalog))


def _learned(s: RunSettings, catalog: Catalog | None) -> dict[str, Any]:
    """The learned sentences and warnings of the record's example settings, by field."""
    if not s.examples:
        return {}
    return learned_options(list(s.examples), catalog or Catalog.load(s.catalog_files),
                           "--examples")


def learned_options(examples: Sequence[str | PathLike[str] | Mapping[str, Any]],
                    catalog: Catalog, given_as: str) -> dict[str, Any]:
    """The :class:`ArrangeOptions` fields (``learned``, ``learned_warnings``) of the
    sentences learned exactly from ``examples`` (files or parsed documents), each warning
    and disagreement prefixed with ``given_as`` (how the user gave them)."""
    from llm_grop.arrangement.learning import learn

    learning = learn(examples, catalog)
    return {"learned": tuple((x.sentence, x.sources) for x in learning.sentences),
            "learned_warnings": tuple(f"{given_as}: {w}" for w in learning.warnings)
            + tuple(f"{given_as}: {c.message()}" for c in learning.contradictions)}


def sampling(s: RunSettings) -> SamplingParams:
    """The decoding settings of every LLM call the record ``s`` makes."""
    return SamplingParams(**{name: getattr(s, name) for name in _SAMPLING})


def planner_options(s: RunSettings, base: GropOptions | None = None) -> GropOptions:
    """The task-motion planner's options the record ``s`` sets, on ``base``'s others."""
    return replace(base or GropOptions(), w=s.weight, fidelity_w_s_per_cm=s.fidelity_weight)


def backend_options(s: RunSettings, base: BackendOptions | None = None) -> BackendOptions:
    """How to build the record's LLM backend, on ``base``'s others (key, threads)."""
    return replace(base or BackendOptions(), model=s.model, base_url=s.base_url,
                   timeout_s=s.timeout_s, max_retries=s.retries,
                   max_answer_bytes=s.max_answer_bytes,
                   replay_path=Path(s.replay) if s.replay is not None else None)


def execution_policy(s: RunSettings, base: ExecutionPolicy | None = None) -> ExecutionPolicy:
    """The executive's policy the record ``s`` sets, on ``base``'s tolerances."""
    return replace(base or ExecutionPolicy(), nav_attempts=s.nav_attempts,
                   manip_attempts=s.manip_attempts)


def call_log(llm: LLM, *, record: str | PathLike[str] | None = None,
             cache: str | PathLike[str] | None = None, chosen_by: str | None = None,
             max_answer_bytes: int = DEFAULTS.max_answer_bytes) -> CallLog:
    """A fresh log of ``llm``'s calls: appended to the JSONL file ``record``, answered
    from the LLM cache in directory ``cache`` where asked before (``None``: neither).
    The one way the API, the bench's trials and the service log an LLM; a backend kept
    from run to run starts each log afresh (:meth:`~llm_grop.llm.base.BaseLLM.for_run`)."""
    if isinstance(llm, BaseLLM):
        llm = llm.for_run()  # type: ignore[assignment]
    return CallLog(llm, Path(record) if record is not None else None,
                   cache=LLMCache(cache, max_answer_bytes) if cache is not None else None,
                   chosen_by=chosen_by)


def make_backend(s: RunSettings, base: BackendOptions | None = None) -> LLM:
    """The record's LLM backend with its own options, built (a model is loaded) now;
    ``auto`` is resolved first (:func:`resolve_llm`)."""
    s, _ = resolve_llm(s)
    return create_llm(s.llm, backend_options(s, base), own=dict(s.backend_options))


def resolve_llm(s: RunSettings) -> tuple[RunSettings, AutoChoice | None]:
    """The record ``s`` with ``llm="auto"`` replaced by what it chooses
    (:mod:`llm_grop.llm.auto`: the backend, its server and model), and the choice
    (``None``: the backend was named). A probed port that answered but was skipped is a
    logged warning."""
    if s.llm != AUTO:
        return s, None
    from llm_grop.llm.auto import choose

    choice = choose(s.model, s.base_url)
    for skipped in choice.skipped:
        log.warning("--llm auto: %s", skipped)
    # Said once the run is done (its LLM line), after any bad input is reported alone.
    log.info("--llm auto: %s", choice.note)
    return s.with_values(llm=choice.backend, base_url=choice.base_url,
                         model=choice.model), choice


def check_backend(s: RunSettings) -> None:
    """:class:`~llm_grop.errors.BadInput` for a backend the record ``s`` cannot use, found
    before any work: an unknown name, options it does not declare, or ``replay`` without
    its file."""
    from llm_grop.errors import BadInput
    from llm_grop.llm.registry import backend_options_class
    from llm_grop.settings.declared import declared_options

    if s.llm == AUTO:
        return  # its options are checked once it has chosen
    key = BACKENDS.key(s.llm)
    declared_options(backend_options_class(key), dict(s.backend_options),
                     owner=f"LLM backend {key!r}", param="backend_options")
    if key == "replay" and s.replay is None:
        raise BadInput("needs replay=FILE, a JSONL file of recorded calls", param="llm",
                       value="replay", mentions=("replay",))


def with_robot_settings(scene: Scene, s: RunSettings) -> Scene:
    """``scene`` with the robot as the record ``s`` sets it (its ``capacity``)."""
    if s.capacity is None or s.capacity == scene.robot.capacity:
        return scene
    return replace(scene, robot=replace(scene.robot, capacity=s.capacity))


def make_simulator(s: RunSettings) -> Simulator:
    """The simulator the record ``s`` names, with its options."""
    from llm_grop.simulation.registry import create_simulator

    return create_simulator(s.simulator, dict(s.sim_options), grasp=s.grasp, truth=s.truth)


def resolve_feasibility(s: RunSettings, simulator: Simulator | None = None) -> RunSettings:
    """The record ``s`` with ``feasibility="auto"`` replaced by the profile fitted to the
    simulator that executes (``simulator``, else the one ``s`` names:
    :meth:`~llm_grop.simulation.base.Simulator.fitted_profile`), so that the run JSON
    and an experiment's identity name the profile the planner used."""
    if s.feasibility != AUTO:
        from llm_grop.errors import BadInput
        from llm_grop.files.profiles import profile_names

        if s.feasibility not in profile_names():
            raise BadInput(f"unknown profile {s.feasibility!r}; choose from "
                           f"{', '.join([AUTO, *profile_names()])}", param="feasibility")
        return s
    sim = simulator if simulator is not None else make_simulator(s)
    return s.with_values(feasibility=sim.fitted_profile())


def seat_diners(top: Table, s: RunSettings, where: str = "the table") -> Table:
    """``top`` with the record's ``diners`` (``--diners``) seated round it: evenly along a
    rectangle's long sides or round a circle
    (:func:`~llm_grop.geometry.places.default_seats`), so that a request for one setting
    is set once for each; ``top`` itself without ``diners`` or when it already seats that
    many (one diner at a top without seats included). Apply it after the record's
    ``table``.

    Raises :class:`~llm_grop.errors.BadInput` (``diners``) when ``top`` (at ``where``)
    seats another number.
    """
    from llm_grop.errors import BadInput
    from llm_grop.geometry.places import default_seats

    if s.diners is None or s.diners == len(top.diners) or (s.diners == 1 and not top.diners):
        return top  # one diner without a seat is the paper's table, as without --diners
    if top.diners:
        raise BadInput(f"{s.diners} diners, but {where} seats {len(top.diners)}; give "
                       f"{len(top.diners)} or leave it out", param="diners")
    return top.with_diners(default_seats(top, s.diners))


def seat_scene_diners(scene: Scene, s: RunSettings) -> Scene:
    """``scene`` with the record's ``diners`` seated at its target table
    (:func:`seat_diners`)."""
    top = seat_diners(scene.target_top, s, f"the scene's {scene.target_table.name!r}")
    return scene if top.diners == scene.diners else replace(scene, diners=top.diners)


def check_recordings(s: RunSettings) -> None:
    """:class:`~llm_grop.errors.BadInput` when a recording the record ``s`` asks for
    cannot be written (its extra missing, a path that cannot be written), before any
    work."""
    from llm_grop.recording.episode import check_recording

    check_recording("rerun", s.rerun)
    check_recording("mcap", s.mcap)


def open_recordings(s: RunSettings) -> Episode | None:
    """The episode stream to the recordings the record ``s`` asks for (``None``: none),
    each file opened now; the caller closes it."""
    from llm_grop.recording.episode import open_episode

    return open_episode(rerun=s.rerun, mcap=s.mcap)


def named_llm(llm: Any, overrides: dict[str, Any]) -> tuple[Any, dict[str, Any]]:
    """``llm`` as an object (``None``: the record's backend); a name given as ``llm`` is
    the ``llm`` setting."""
    overrides = dict(overrides)
    given = overrides.pop("llm", None) if llm is None else None
    if isinstance(llm, str):
        overrides["llm"], llm = llm, None
    elif given is not None and not isinstance(given, str):
        llm = given
    elif given is not None:
        overrides["llm"] = given
    return llm, overrides


def named_simulator(simulator: Any, overrides: dict[str, Any]) -> tuple[Any, dict[str, Any]]:
    """``simulator`` as an object (``None``: the record's); a name is the setting."""
    overrides = dict(overrides)
    if isinstance(simulator, str):
        overrides["simulator"], simulator = simulator, None
    return simulator, overrides


def named_scene(scene: Any, overrides: dict[str, Any]) -> tuple[Any, dict[str, Any]]:
    """``scene`` as a :class:`Scene` (``None``: the record's file); a path is the
    setting."""
    overrides = dict(overrides)
    given = overrides.pop("scene", None)
    scene = scene if scene is not None else given
    if scene is not None and not isinstance(scene, Scene):
        overrides["scene"], scene = str(scene), None
    return scene, overrides


@dataclass(frozen=True)
class RunInputs:
    """What a caller of the API gave for one run: the settings record (with the overrides
    applied), and besides it component records whole, an LLM object, a scene object, a
    table with seats, other tasks, a file to record the LLM's calls to."""

    settings: RunSettings
    bases: Bases
    llm: LLM | CallLog | None = None
    scene: Scene | None = None
    table: Table | None = None
    tasks: Mapping[int, Task] | None = None
    record: str | PathLike[str] | None = None

    @classmethod
    def of(cls, settings: RunSettings | None, llm: Any, scene: Any,
           overrides: dict[str, Any]) -> RunInputs:
        """The job ``settings`` with ``overrides`` describe (objects apart)."""
        llm, overrides = named_llm(llm, overrides)
        scene, overrides = named_scene(scene, overrides)
        tasks = overrides.pop("tasks", None)
        record = overrides.pop("record", None)
        table = overrides.get("table")
        if isinstance(table, Table):
            overrides["table"] = table.text
        else:
            table = None
        s, bases = settle(settings, overrides)
        if table is None and s.table is not None:
            table = Table.parse(s.table)
        return cls(s, bases, llm, scene, table, tasks, record)

    def log(self) -> CallLog:
        """A fresh call log over the job's LLM (built now when it is a backend's name)."""
        if isinstance(self.llm, CallLog):
            return self.llm
        check_backend(self.settings)
        if self.llm is not None:
            return call_log(self.llm, record=self.record, cache=self.settings.cache,
                            max_answer_bytes=self.settings.max_answer_bytes)
        settings, choice = resolve_llm(self.settings)
        check_backend(settings)
        return call_log(make_backend(settings, self.bases.backend), record=self.record,
                        cache=settings.cache, chosen_by=choice.why if choice else None,
                        max_answer_bytes=settings.max_answer_bytes)
