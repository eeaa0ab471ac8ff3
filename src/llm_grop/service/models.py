"""The service's JSON API as typed models: what a client sends (strict: unknown keys,
wrong types and file paths are refused) and what it gets back. FastAPI publishes them as
the OpenAPI document (``docs/schema/openapi.json``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, StrictBool, StrictInt

from llm_grop.contract.models import ArrangementDoc, RelationDoc, RunDoc
from llm_grop.contract.plan_doc import PlanJSON
from llm_grop.datafile import problem_line
from llm_grop.settings import DEFAULTS, RunSettings, help_text
from llm_grop.world.request import MAX_REQUEST_CHARS
from llm_grop.world.table import MAX_TABLE_SIDE_M, MIN_TABLE_SIDE_M, Table

if TYPE_CHECKING:
    from llm_grop.arrangement.learning import Learning


def setting(name: str, base: Any, *limits: Any) -> Any:
    """The settings record's field ``name`` as a JSON body's type: ``base`` (a strict
    pydantic type) with the record's bounds and the server's own ``limits`` on top."""
    return Annotated[(base, *RunSettings.model_fields[name].metadata, *limits)]


def described(name: str, **more: Any) -> Any:
    """A JSON body's field with the settings record's default and help for ``name``."""
    return Field(getattr(DEFAULTS, name), description=help_text(name), **more)


def _no_path(text: str) -> str:
    # A name a client sends picks among what the server has; it is never a file to open.
    if "/" in text or "\\" in text or text.startswith(("~", ".")):
        raise ValueError(f"{text!r} looks like a file path; the server never reads files a "
                         "client names, give a name it offers")
    return text


Name = Annotated[str, Field(strict=True, min_length=1, max_length=64),
                 AfterValidator(_no_path)]
Sentence = Annotated[str, Field(strict=True, min_length=1, max_length=300)]
#: A request's text: the server's own limit (``Limits.request_chars``) is checked after.
RequestText = Annotated[str, Field(strict=True, min_length=1, max_length=MAX_REQUEST_CHARS)]
Side = Annotated[float, Field(strict=False, ge=MIN_TABLE_SIDE_M, le=MAX_TABLE_SIDE_M,
                              allow_inf_nan=False)]
Coordinate = Annotated[float, Field(allow_inf_nan=False, ge=-100, le=100)]


#: One value of a plugin's option: what a ``KEY=VALUE`` flag's YAML value may be.
OptionScalar = Annotated[str, Field(strict=True, max_length=300)] | StrictBool | StrictInt \
    | Annotated[float, Field(strict=True, allow_inf_nan=False)] | None
OptionValue = OptionScalar | Annotated[list[OptionScalar], Field(max_length=16)]
#: A plugin's own options by name, checked against what it declares when the job runs.
PluginOptions = Annotated[dict[Annotated[str, Field(min_length=1, max_length=64)],
                               OptionValue], Field(max_length=32)]


def plugin_options(what: str) -> Any:
    """A body's field of ``what``'s own options (``--sim-option`` and the like on the
    command line)."""
    return Field({}, description=f"the {what}'s own options by name, as it declares them "
                                 "(`llm-grop plugins` lists them); options naming files are "
                                 "refused")


class _Body(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class TableBody(_Body):
    """The target table's top: a rectangle ``[width, depth]`` or a circle ``[d, d]``,
    metres."""

    shape: Literal["rectangle", "circle"] = "rectangle"
    size: tuple[Side, Side]

    def table(self) -> Table:
        """As the pipeline's table."""
        if self.shape == "circle":
            return Table.circle(self.size[0])
        return Table(self.size[0], self.size[1])


class ArrangeBody(_Body):
    """``POST /v1/arrangements``: arrange the objects of a request on a table."""

    request: RequestText = Field(description="the request in the user's words")
    table: TableBody | None = Field(None, description="default: 0.9 x 0.6 m")
    diners: setting("diners", StrictInt) | None = Field(
        None, description="seat this many diners, one setting each (default: as the request "
                          "says)")
    preferences: list[Sentence] = Field([], max_length=20, description="relations the user "
                                        "wants, e.g. 'the dinner fork to the left of the "
                                        "dinner plate'; they win over the LLM")
    examples: list[dict[str, Any]] = Field(
        [], max_length=20, description="example table settings to learn preferences from, as "
        "POST /v1/preferences does (each the contract's arrangement JSON, or a run JSON); "
        "what holds in every example applies as `preferences` do, with source `learned`")
    llm: Name | None = Field(None, description="one of the server's backends (GET /v1/info); "
                                               "default: its first")
    seed: setting("seed", StrictInt) = described("seed")
    m: setting("m", StrictInt, Field(le=100)) = described("m")
    revisions: setting("revisions", StrictInt) | None = described("revisions")
    guess: StrictBool = described("guess")


class ChairBody(_Body):
    """A sensed chair: its footprint's centre and size, metres, and yaw, radians (room
    frame)."""

    center: tuple[Coordinate, Coordinate]
    size: tuple[Annotated[float, Field(gt=0, le=3)], Annotated[float, Field(gt=0, le=3)]]
    yaw: Annotated[float, Field(allow_inf_nan=False)] = 0.0


class PlanBody(_Body):
    """``POST /v1/plans``: a task-motion plan for a request (or a given arrangement) in a
    room."""

    request: RequestText | None = None
    task: Annotated[StrictInt, Field(ge=1, le=100)] | None = Field(
        None, description="the paper's Table I task instead of a request")
    arrangement: dict[str, Any] | None = Field(
        None, description="an arrangement JSON to plan for as it is, instead of a request")
    table: TableBody | None = Field(None, description="replaces the scene's target top")
    diners: setting("diners", StrictInt) | None = described("diners")
    preferences: list[Sentence] = Field([], max_length=20)
    examples: list[dict[str, Any]] = Field(
        [], max_length=20, description="example table settings to learn preferences from, as "
        "POST /v1/preferences does (each the contract's arrangement JSON, or a run JSON); "
        "what holds in every example applies as `preferences` do, with source `learned`")
    scene: dict[str, Any] | None = Field(
        None, description="the room as a scene document (the run JSON's scene; default: the "
                          "packaged dining room)")
    chairs: list[ChairBody] | None = Field(
        None, max_length=40, description="the chairs the robot senses; they replace the "
                                         "scene's (default: the scene's own, else one is "
                                         "sampled for the seed)")
    robot: tuple[Coordinate, Coordinate, Annotated[float, Field(allow_inf_nan=False)]] | None \
        = Field(None, description="the robot's pose [x, y, theta] in the room frame")
    capacity: setting("capacity", StrictInt) | None = described("capacity")
    method: Name = described("method")
    method_options: PluginOptions = plugin_options("method")
    feasibility: Name = described("feasibility")
    llm: Name | None = None
    seed: setting("seed", StrictInt) = described("seed")
    m: setting("m", StrictInt, Field(le=100)) = described("m")
    revisions: setting("revisions", StrictInt) | None = described("revisions")
    guess: StrictBool = described("guess")


class RunBody(PlanBody):
    """``POST /v1/runs``: plan and execute in a simulator, as a job."""

    simulator: Name = described("simulator")
    sim_options: PluginOptions = plugin_options("simulator")
    video: StrictBool = Field(True, description="mujoco: record a video of the episode")


class ErrorAnswer(BaseModel):
    """Every refusal: the project's one-line message and a code for programs."""

    error: str
    code: Literal["bad_input", "infeasible", "unauthorized", "forbidden", "not_found",
                  "too_large", "overloaded", "internal", "timeout", "method_not_allowed",
                  "bad_host", "not_json", "bad_range", "llm_unavailable", "bad_json"]


class ReadObject(BaseModel):
    """One object as the request was read: its name, kind, where it came from and the
    request's words it was read from."""

    name: str
    kind: str
    source: str | None = None
    words: str | None = None


class Reading(BaseModel):
    """How the request was read: by the catalog matcher or an LLM, the objects and the
    relations with their sources."""

    read_by: str | None
    objects: list[ReadObject]
    relations: list[RelationDoc]


class ArrangementAnswer(BaseModel):
    """``POST /v1/arrangements``' answer."""

    id: str
    arrangement: ArrangementDoc
    reading: Reading
    warnings: list[str]
    picture: str = Field(description="URL of the arrangement's PNG picture")
    permalink: str


class PlanAnswer(BaseModel):
    """``POST /v1/plans``' answer: the plan a robot stack executes."""

    id: str
    plan: PlanJSON
    reading: Reading
    warnings: list[str]
    picture: str = Field(description="URL of the planned arrangement's PNG picture")
    room_picture: str = Field(description="URL of the plan drawn on the room, PNG")
    permalink: str


class JobAnswer(BaseModel):
    """A job: ``POST /v1/runs``' answer and ``GET /v1/runs/{id}``. Times are seconds since
    the epoch."""

    id: str
    kind: str
    state: Literal["queued", "running", "done", "failed", "cancelled"]
    created: float
    started: float | None = None
    finished: float | None = None
    attempts: int
    error: str | None = None
    status: int | None = Field(None, description="a failure's HTTP status: 422 bad input, "
                                                 "409 nothing feasible, 504 over time")
    result: RunDoc | dict[str, Any] | None = None
    files: dict[str, str] = Field({}, description="file name -> URL: pictures, 3D renders, "
                                                  "the video")
    events: str = Field(description="URL of the progress events (text/event-stream)")
    permalink: str


class Pending(BaseModel):
    """An arrangement or plan not ready within the server's wait (202): its id, state and
    the permalink its answer will be at."""

    id: str
    state: str
    permalink: str


class Info(BaseModel):
    """``GET /v1/info``: what this server offers."""

    version: str
    backends: list[str]
    methods: list[str]
    simulators: list[str]
    limits: dict[str, int | float] = Field(
        description="the server's limits: counts and bytes as whole numbers, seconds as numbers")
    queue: dict[str, int]


def reading(doc: ArrangementDoc) -> Reading:
    """The reading held in an arrangement document."""
    return Reading(read_by=doc.request_read_by,
                   objects=[ReadObject(name=o.name, kind=o.kind or o.name, source=o.source,
                                       words=o.words) for o in doc.objects],
                   relations=list(doc.relations))


def one_line(errors: Sequence[Any], raw: Any = None, model: Any = None,
             where: str | None = "body") -> str:
    """The first of pydantic's validation ``errors`` about the body ``raw`` (of ``model``)
    as ``field: reason``, in the words of the project's data files
    (:func:`~llm_grop.datafile.problem_line`)."""
    return problem_line(errors, raw, model, where=where)


class PreferencesBody(_Body):
    """``POST /v1/preferences``: learn a person's way of setting the table from example
    settings, as ``llm-grop learn`` does: exactly (``--exact``), or with ``generalise`` as
    a job that asks the server's LLM for rules for the objects the examples do not show."""

    examples: list[dict[str, Any]] = Field(
        min_length=1, max_length=20,
        description="table settings: each the contract's arrangement JSON, or a run JSON "
                    "(its `final`, what was set); one or several diners")
    generalise: StrictBool = Field(
        False, description="also ask the LLM where the same person would put the catalog's "
                           "objects the examples do not show (one call; a job, answered "
                           "when done or with 202 and its permalink)")
    llm: Name | None = Field(None, description="with generalise: one of the server's "
                                               "backends (GET /v1/info); default: its first")
    seed: setting("seed", StrictInt) = described("seed")


class LearnedPreference(BaseModel):
    """One learned sentence: its gap's median and the smallest and largest seen,
    centimetres (``null`` for stacking and a distance from the diner's edge has its own),
    and the settings it holds in (``example N``, with ``(diner k)`` for one diner's)."""

    sentence: str
    gap_cm: float | None
    spread_cm: tuple[float, float] | None
    examples: list[str]


class PreferencesAnswer(BaseModel):
    """``POST /v1/preferences``' answer: the learned sentences, what the examples disagree
    on (not learned), the warnings, and the preferences file (YAML, for
    ``--preferences``)."""

    preferences: list[LearnedPreference]
    not_learned: list[str]
    warnings: list[str]
    file: str
    id: str | None = Field(None, description="with generalise: the job's id")
    permalink: str | None = Field(None, description="with generalise: where the answer "
                                                    "stays")


def preferences_answer(learned: Learning) -> PreferencesAnswer:
    """The answer for a :class:`~llm_grop.arrangement.learning.Learning`."""
    return PreferencesAnswer(
        preferences=[LearnedPreference(sentence=s.sentence, gap_cm=s.gap_cm,
                                       spread_cm=s.spread_cm, examples=list(s.sources))
                     for s in learned.sentences],
        not_learned=[c.message() for c in learned.contradictions],
        warnings=list(learned.warnings), file=learned.preference_file())
