"""The stable JSON contract as typed models: the arrangement JSON, the run JSON and the bench's
trial row (``../shared/design/contract.md``).

Every writer builds these models and every reader validates through them, the rater
included. Their JSON Schemas are generated from them (:func:`json_schema`), committed under
``docs/schema/`` and printed by ``llm-grop schema NAME``.

The contract only grows: fields are added, never renamed or removed, so every model keeps
fields it does not know (``extra="allow"``), and a reader of this version accepts a file a
later version wrote. Optional keys are left out of a document, not written as ``null``,
unless ``null`` has a meaning of its own (``on``, ``reference``, ``task``).

Units: metres, radians and seconds. Table-frame poses: origin at the table top's centre,
+x to the diner's right, +y away from the diner. Room-frame poses: ``[x, y, theta]`` in
the dining room's map.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, Strict, model_validator

from llm_grop.files.scene_file import SceneFile
from llm_grop.world.plan import Reason
from llm_grop.world.relation import RELATION_NAMES


def _not_blank(text: str) -> str:
    if not text.strip():
        raise ValueError("expected a non-empty string")
    return text


Num = Annotated[float, Strict(), Field(allow_inf_nan=False)]
Seconds = Annotated[float, Strict(), Field(ge=0, allow_inf_nan=False)]
Length = Annotated[float, Strict(), Field(gt=0, allow_inf_nan=False)]
Int = Annotated[int, Strict()]
Bool = Annotated[bool, Strict()]
Text = Annotated[str, Strict()]
Name = Annotated[str, Strict(), AfterValidator(_not_blank)]
Size = Annotated[tuple[Length, Length], Field(description="[sx, sy] in metres")]
RoomPose = Annotated[tuple[Num, Num, Num],
                     Field(description="room-frame [x, y, theta]: metres, metres, radians")]
RelationName = Literal[RELATION_NAMES]  # type: ignore[valid-type]


class Doc(BaseModel):
    """A part of a contract document: keeps fields it does not know."""

    model_config = ConfigDict(extra="allow", frozen=True)

    def to_json(self) -> dict[str, Any]:
        """The document as JSON values, optional keys that were never set left out."""
        return self.model_dump(mode="json", exclude_unset=True)


class TableDoc(Doc):
    """The target table's top: ``size`` is ``[width, depth]`` in metres (``[d, d]`` for a
    round one)."""

    shape: Literal["rectangle", "circle"] = "rectangle"
    size: Size
    diners: list[tuple[Num, Num, Num]] | None = Field(
        None, description="the diners' seat poses [x, y, yaw] in the table frame (yaw: the "
                          "way the diner faces); absent: one diner at the -y edge")

    @model_validator(mode="after")
    def _round_is_square(self) -> TableDoc:
        # A circle has one size; [1.2, 0.8] would be a round table in a rectangular frame.
        if self.shape == "circle" and abs(self.size[0] - self.size[1]) > 1e-6:
            raise ValueError(f"a round table (shape circle) has one size, its diameter: "
                             f"expected [d, d], got [{self.size[0]:g}, {self.size[1]:g}]")
        return self


class ObjectDoc(Doc):
    """One object on the table, in the table frame.

    llm-grop always writes every field; a reader fills ``shape``, ``size`` and ``height``
    in from the catalog when another system leaves them out.
    """

    name: Name = Field(description="unique name: the catalog kind, numbered from the "
                                   "second of a kind ('dinner fork 2')")
    x: Num = Field(description="metres, table frame")
    y: Num = Field(description="metres, table frame")
    yaw: Num = Field(0.0, description="radians: the object's own frame to the table frame, "
                                      "counter-clockwise")
    shape: Literal["circle", "box"] | None = None
    size: Size | None = Field(None, description="footprint [sx, sy] in metres in the "
                                                "object's own frame; circles use [d, d]")
    on: Name | None = Field(None, description="the object this one rests on; null: the table")
    diner: Annotated[int, Strict(), Field(ge=0)] | None = Field(
        None, description="index into table.diners of the diner whose setting this object "
                          "belongs to; null: a shared object, or the one diner")
    kind: Name | None = Field(None, description="the catalog kind (default: the name without "
                                                "a trailing number)")
    height: Annotated[float, Strict(), Field(ge=0, allow_inf_nan=False)] | None = Field(
        None, description="metres")
    source: Literal["request", "llm", "task"] | None = Field(
        None, description="where the object came from: the request names it, the LLM chose "
                          "it (the request does not name it, or not how many), or the "
                          "paper's task lists it")
    words: Text | None = Field(None, description="the request's words it was read from")
    z_m: Num | None = Field(None, description="after execution: height of the object's base "
                                              "above the table top, metres")
    tilt_rad: Annotated[float, Strict(), Field(ge=0, allow_inf_nan=False)] | None = Field(
        None, description="after execution: angle between the object's up axis and the "
                          "vertical, radians")


class RelationDoc(Doc):
    """``subject relation reference``; ``reference`` is ``null`` for ``center``. ``line`` (in
    ``conflicts`` only) is the LLM's text the relation was read from."""

    subject: Name
    relation: RelationName
    reference: Name | None
    line: Text | None = None
    source: Literal["llm", "preference", "request", "revision", "learned"] | None = Field(
        None, description="where the relation came from: the LLM's answer, a stated "
                          "preference, the request's own words, the LLM's revision after "
                          "a failure was explained to it (with `revision`), or example "
                          "settings it was learned from (with `examples`)")
    words: Text | None = Field(None, description="the request's words that state it "
                                                 "(source request)")
    gap_m: Num | None = Field(None, description="the gap between the objects' edges the "
                                                "user stated, metres")
    revision: Annotated[int, Strict(), Field(ge=1)] | None = Field(
        None, description="the round of the feedback loop (`revisions[].round`) whose answer "
                          "first stated it, after a failure was explained to the LLM (source "
                          "revision); absent: the LLM's first answer, or another source")
    examples: list[Text] | None = Field(
        None, description="the example settings a learned relation was read off (source "
                          "learned): their files, and `(diner k)` for one diner's setting")


class LLMCallDoc(Doc):
    """One logged LLM call: latency in seconds; token counts ``null`` when unknown."""

    prompt: Text
    response: Text
    latency_s: Seconds
    prompt_tokens: Int | None = None
    completion_tokens: Int | None = None
    seed: Int | None = None
    cached: bool | None = Field(None, description="true when the LLM cache answered the call "
                                                  "(its latency is the original call's); "
                                                  "absent otherwise")


class LLMDoc(Doc):
    """Which model arranged the objects, how many calls it took, and (``log``) each call."""

    backend: Text
    model: Text
    calls: Int
    log: list[LLMCallDoc] | None = None
    chosen_by: Text | None = Field(
        None, description="how `--llm auto` chose this backend and model, in one line "
                          "(absent: they were named)")


class FailureDoc(Doc):
    """Why relations could not be realised, as the feedback loop told the LLM."""

    kind: Literal["logical", "geometric", "physical"] = Field(
        description="logical: the relations contradict each other (clingo); geometric: no "
                    "placement on the table keeps them (the sampler); physical: the robot "
                    "could not carry out the plan (the executive)")
    reason: Text = Field(description="the failure in plain words")
    objects: list[Name] = Field([], description="the objects involved")
    relations: list[RelationDoc] = Field([], description="the relations involved (logical: "
                                                         "the minimal conflicting set)")


class RevisionDoc(Doc):
    """One round of the feedback loop: a failure told to the LLM and what came of it."""

    round: Annotated[int, Strict(), Field(ge=1)]
    failure: FailureDoc
    asked: Text = Field(description="the prompt that told the LLM what failed and why")
    answer: Text | None = Field(None, description="the LLM's answer (absent: none was "
                                                  "available, e.g. a replay without it)")
    outcome: Literal["accepted", "refused"] = Field(
        description="accepted: the revised relations replaced the failed ones; refused: "
                    "the answer held no usable relation, repeated the failed ones or "
                    "contradicted itself, and the original failure stands")
    note: Text | None = Field(None, description="why a revision was refused")
    added: list[RelationDoc] = Field([], description="relations the revision states that "
                                                     "the failed proposal did not")
    removed: list[RelationDoc] = Field([], description="relations of the failed proposal "
                                                       "the revision no longer states")


class ArrangementDoc(Doc):
    """The arrangement JSON: ``llm-grop arrange --json``, and ``final``/``planned`` in a run."""

    model_config = ConfigDict(title="llm-grop arrangement JSON")

    request: Text = ""
    table: TableDoc
    objects: list[ObjectDoc]
    relations: list[RelationDoc] = Field(
        [], description="the consistent symbolic relations the arrangement satisfies")
    llm: LLMDoc | None = None
    warnings: list[Text] = Field([], description="what the pipeline dropped or assumed")
    conflicts: list[list[RelationDoc]] = Field(
        [], description="per rejected LLM answer, the minimal set of conflicting lines")
    revisions: list[RevisionDoc] | None = Field(
        None, description="the feedback loop's rounds, in order (absent: no failure was "
                          "explained to the LLM)")
    request_read_by: Literal["catalog", "llm"] | None = Field(
        None, description="how the request was read: by the catalog matcher alone (also "
                          "for the paper's tasks, whose objects are listed), or by an LLM "
                          "that read the whole request")


class StepDoc(Doc):
    """One executed action (an attempt; failed attempts are kept, ``ok`` false, with a
    ``note``). ``pose`` is where a placed object landed (table frame ``[x, y, yaw]``) or,
    for ``pick``, the object's start (room frame ``[x, y, 0]``)."""

    action: Literal["navigate", "pick", "place"]
    object: Text | None = None
    goal: RoomPose | None = None
    standing: RoomPose | None = None
    pose: tuple[Num, Num, Num] | None = None
    duration_s: Seconds
    ok: Bool
    attempt: Int = 1
    note: Text | None = None
    path: list[tuple[Num, Num]] | None = Field(None, description="the driven path, room "
                                                                 "frame, metres")
    reason: Reason | None = Field(None, description="why a failed attempt failed, from one "
                                                    "closed list")
    arrival_error_m: Num | None = Field(
        None, description="navigate: distance from where the base stopped to its goal, "
                          "metres")
    arrival_yaw_error_rad: Num | None = Field(
        None, description="navigate: absolute difference between the base's heading and "
                          "the goal's, radians")
    tray: Bool | None = Field(
        None, description="true for a place onto the robot's tray (loading) and a pick from "
                          "it (unloading); absent otherwise")


class StandingDoc(Doc):
    """Where the plan has the robot stand to place ``object``."""

    object: Name
    pose: RoomPose


class GapDoc(Doc):
    """One relation's gap between edges: as stated (by the LLM or a preference) and as
    realised in the configuration, metres."""

    subject: Name
    relation: RelationName
    reference: Name
    stated_m: Num
    realised_m: Num
    error_m: Num = Field(description="realised minus stated, metres")


class FidelityDoc(Doc):
    """How faithfully a configuration keeps the stated geometry (metres)."""

    infidelity_m: Num = Field(description="summed |realised - stated| over the gaps plus the "
                                          "origin's shift; what the fidelity weight charges")
    max_gap_error_m: Num = Field(description="largest |realised - stated| over the gaps and "
                                             "the distance from the diner's edge")
    origin: Text = Field(description="the layout's origin object ('' when none)")
    origin_shift_m: Num = Field(description="how far the origin lies from its guided position")
    edge_stated_m: Num | None = Field(None, description="the origin's stated distance from "
                                                        "the diner's edge of the table")
    edge_realised_m: Num | None = None
    gaps: list[GapDoc] | None = Field(None, description="per relation (chosen configuration "
                                                        "only)")


class ConsideredDoc(Doc):
    """One of the M configurations as GROP scored it; ``utility`` and ``score`` are null
    when it has no plan."""

    index: Int
    expected_utility: Num | None
    feasibility: Num | None
    expected_cost_s: Num | None
    score: Num | None = Field(description="expected utility minus the fidelity penalty, s")
    fidelity: FidelityDoc


class PlanFidelityDoc(Doc):
    """The fidelity of the plan's choice: the weight, the chosen configuration's fidelity
    and every configuration evaluated."""

    weight_s_per_cm: Num = Field(description="seconds of utility one centimetre of "
                                             "infidelity costs")
    chosen: FidelityDoc
    configurations: list[ConsideredDoc]


class PlanDoc(Doc):
    """The chosen task-motion plan: expected utility and costs in seconds."""

    order: list[Name]
    standing: list[StandingDoc]
    configuration_index: Int = Field(description="which of the M configurations, from 0")
    configurations: Int = Field(description="M, how many configurations were planned for")
    expected_utility: Num
    feasibility: Num = Field(description="probability that every action succeeds at once")
    expected_cost_s: Num
    expected_duration_s: Num
    fidelity: PlanFidelityDoc | None = Field(None, description="how faithfully the chosen "
                                                               "and the other configurations "
                                                               "keep the stated geometry")


class RunDoc(Doc):
    """The run JSON: ``llm-grop run --json``."""

    model_config = ConfigDict(title="llm-grop run JSON")

    method: Name
    task: Int | None = Field(description="the task id, or null for a free request")
    seed: Int
    request: Text
    success: Bool = Field(description="every requested object ended upright on its "
                                      "intended support, within tolerance of its target")
    execution_time_s: Seconds = Field(description="simulated seconds")
    planning_time_s: Seconds = Field(description="wall-clock seconds, LLM calls excluded")
    failures: Int = Field(description="failed action attempts")
    unplaced: list[Name]
    unplaced_reasons: dict[Name, Reason] | None = Field(
        None, description="why each unplaced object is not in place, from the steps' list")
    steps: list[StepDoc]
    trips: list[list[Name]] | None = Field(
        None, description="with robot.capacity above 1: the objects carried on each trip, "
                          "in the order picked (a trip of several rides on the robot's tray); "
                          "absent with capacity 1, where each object is its own trip")
    final: ArrangementDoc = Field(description="where the objects really ended up")
    plan: PlanDoc
    planned: ArrangementDoc = Field(description="the arrangement the plan realises")
    simulator: Name = Field(description="the simulator that executed the plan")
    feasibility: Name | None = Field(None, description="the planner's feasibility profile "
                                                       "(its belief; --feasibility auto "
                                                       "resolved to the profile fitted to "
                                                       "the simulator; absent in runs of "
                                                       "versions before 0.17.0: default)")
    scene: SceneFile = Field(description="the episode's room, with its sampled chairs and "
                                         "object starts, in the scene file's layout")


class CheckDoc(Doc):
    """One check of the automatic rater."""

    name: Name
    passed: Bool
    severity: Literal["missing", "major", "minor"]
    detail: Text
    skipped: Bool = False


class RatingDoc(Doc):
    """The automatic rater's 1-5 score (paper Table III), with every check behind it."""

    score: Annotated[int, Strict(), Field(ge=1, le=5)]
    summary: Text
    checks: list[CheckDoc]
    diners: list[RatingDoc] | None = Field(None, description="with several diners, each "
                                                             "diner's rating; the score is "
                                                             "the lowest")


class TrialRow(RunDoc):
    """One line of a bench's ``trials.jsonl``: the run JSON of one trial (without the LLM
    call log) plus its rating. A trial without a plan has ``status`` ``infeasible`` (or
    ``llm-failed``), a ``reason``, nothing on the table, and no ``plan``, ``planned`` or
    ``scene``."""

    model_config = ConfigDict(title="llm-grop bench trial row")

    execution_time_s: Seconds | None = Field(description="simulated seconds; null without "
                                                         "a plan")
    planning_time_s: Seconds | None = Field(description="wall-clock seconds; null without "
                                                        "a plan")
    plan: PlanDoc | None = None
    planned: ArrangementDoc | None = None
    scene: SceneFile | None = None
    simulator: Name | None = Field(None, description="the simulator that executed the plan; "
                                                     "absent in rows written before 0.2")
    status: Literal["ok", "infeasible", "llm-failed"] = Field(
        description="ok; infeasible: no plan exists; llm-failed: the LLM could not be "
                    "reached or answered badly after its retries (left out of the summary's "
                    "means, and retried by a rerun; since 0.13)")
    reason: Text | None = None
    trial: Int
    retries: Int = Field(description="actions that needed more than one attempt")
    llm_calls: Int
    llm_prompt_tokens: Int
    llm_completion_tokens: Int
    llm_time_s: Seconds = Field(description="wall-clock seconds waiting for the LLM")
    llm_cache_hits: Int | None = Field(None, description="LLM calls the cache answered (which "
                                                         "trial asks first depends on "
                                                         "scheduling); absent in rows "
                                                         "written before 0.7")
    rating: Annotated[int, Strict(), Field(ge=1, le=5)]
    rating_explanation: RatingDoc
    image: Text | None = Field(None, description="the final table's picture, relative to "
                                                 "the results directory")
    render: Text | None = Field(None, description="a 3D simulator's top-down render of the "
                                                  "final table, relative to the results "
                                                  "directory")
    recording: Text | None = Field(None, description="the episode's Rerun recording (.rrd, "
                                                     "bench --rerun), relative to the "
                                                     "results directory")
    task: Int = Field(description="the task id")
    requested: list[Name] | None = Field(None, description="the task's objects, as the "
                                                          "picture lists them at its top; "
                                                          "absent in rows written before "
                                                          "0.6")
