"""The settings record itself: :class:`RunSettings`, its fields' metadata (:class:`Door`,
:func:`setting`) and :data:`DEFAULTS`."""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PlainSerializer,
    ValidationError,
    WithJsonSchema,
)

from llm_grop.errors import BadInput
from llm_grop.settings.reasons import problem, unknown_words

#: The front doors a setting comes through; each names a field its own way.
Interface = Literal["python", "cli", "sweep", "json", "web"]

#: How MuJoCo's hand holds an object: ``fix``, a weld that attaches only on a squeezing
#: grip (Gazebo's grasp-fix), or ``friction``, contact friction alone.
Grasp = Literal["fix", "friction"]

#: The largest seed: a 32-bit generator seed.
MAX_SEED = 2**31 - 1


@dataclass(frozen=True)
class Door:
    """How one front door spells a setting, where it differs from the field's name.

    ``cli``: the flag (``--configurations``; ``None``: ``--`` and the name with ``-`` for
    ``_``), ``short``: a one-letter alias (``-m``), ``negate``: a flag that sets a boolean
    to false (``--no-guess`` for ``guess``), ``sweep``: a sweep file's key path
    (``llm.backend``), ``json``: the service's JSON field, ``metavar``: the flag's
    placeholder, ``path``: the value names a ``file`` or a ``dir``, ``cli_help``: the
    flag's help where the record's own words name Python's values, ``web``: what a user of
    the playground does to give the value a message mentions (its own control).
    """

    cli: str | None = None
    short: str | None = None
    negate: str | None = None
    sweep: str | None = None
    json: str | None = None
    metavar: str | None = None
    path: Literal["file", "dir"] | None = None
    cli_help: str | None = None
    web: str | None = None


def setting(default: Any, help: str, *, group: str, door: Door | None = None,
            identity: bool = True, **bounds: Any) -> Any:
    """A field of :class:`RunSettings`: its default, help (units included), the group of
    options it belongs to (``llm``, ``plan``, ``sim``, ...), how front doors spell it
    (:class:`Door`), whether it is part of an experiment's identity, and pydantic bounds
    (``ge``, ``le``, ``min_length``)."""
    meta: dict[str, Any] = {"group": group, "identity": identity}
    if door is not None:
        # As plain data, so that the record's JSON Schema carries it too.
        meta["door"] = {k: v for k, v in asdict(door).items() if v is not None}
    return Field(default, description=help, json_schema_extra=meta, **bounds)


def _frozen(value: Any) -> Any:
    """``value`` with its lists as tuples, so that a record holding it can be hashed."""
    if isinstance(value, list | tuple):
        return tuple(_frozen(v) for v in value)
    if isinstance(value, Mapping):
        return tuple(sorted((str(k), _frozen(v)) for k, v in value.items()))
    return value


def _pairs(value: Any) -> Any:
    """A mapping of options (or ``KEY=VALUE`` texts, or pairs) as sorted ``(key, value)``
    pairs; a ``KEY=VALUE`` text's value is read as YAML (``0.002``, ``true``, ``[1, 2]``)."""
    if isinstance(value, Mapping):
        return _frozen(value)
    if not isinstance(value, list | tuple):
        return value
    pairs: dict[str, Any] = {}
    for entry in value:
        if isinstance(entry, str):
            key, eq, text = entry.partition("=")
            if not eq or not key.strip():
                raise ValueError(f"expected KEY=VALUE, got {entry!r}")
            import yaml

            try:
                pairs[key.strip()] = yaml.safe_load(text)
            except yaml.YAMLError:
                raise ValueError(f"{key.strip()}: {text!r} is not a value") from None
        elif isinstance(entry, list | tuple) and len(entry) == 2:
            pairs[str(entry[0])] = entry[1]
        else:
            return value
    return _frozen(pairs)


#: A plugin's own options by name (sorted ``(key, value)`` pairs; a mapping, or
#: ``KEY=VALUE`` texts, in), checked by the registry against the ``Options`` the plugin
#: declares (:mod:`llm_grop.settings.declared`).
Pairs = Annotated[tuple[tuple[str, Any], ...], BeforeValidator(_pairs), PlainSerializer(dict),
                  WithJsonSchema({"type": "object"})]


class RunSettings(BaseModel):
    """Everything that shapes one run (units in each field's help). Immutable: build one
    with the constructor (or :meth:`make` from a mapping) and change a copy with
    :meth:`with_values`; a bad value is :class:`BadInput` naming its field."""

    model_config = ConfigDict(frozen=True, extra="forbid", validate_default=False,
                              allow_inf_nan=False)

    # What to set
    task: int | None = setting(
        None, "Use the objects of the paper's Table I task N.", group="what", ge=1)
    method: str = setting(
        "llm-grop", "tpra, latp, grop, llm-grop, or a plugin's (see `llm-grop plugins`).",
        group="what", min_length=1)
    seed: int = setting(
        0, "Seed for the scene's chairs, the LLM, the sampler, the plan and execution.",
        group="what", ge=0, le=MAX_SEED)
    method_options: Pairs = setting(
        (), "An option of the method, KEY=VALUE (a YAML value), as its Options declare them "
            "(`llm-grop plugins` lists them), e.g. draw_box=place; repeatable.",
        group="what", door=Door(cli="--method-option", metavar="KEY=VALUE"))
    task_files: tuple[str, ...] = setting(
        (), "Extra tasks (YAML, like the packaged tasks.yaml); repeatable.", group="what",
        door=Door(cli="--task-file", path="file"))
    catalog_files: tuple[str, ...] = setting(
        (), "An extra object catalog file (repeatable).", group="llm",
        door=Door(cli="--catalog", path="file"))

    # Where
    scene: str | None = setting(
        None, "Dining-room scene YAML (default: the packaged dining room).", group="room",
        door=Door(path="file"))
    chairs: int | None = setting(
        None, "Chairs to sample near the table [default: the scene's own, else 1].",
        group="room", ge=0)
    table: str | None = setting(
        None, "The target table's top: WxD such as 120x80cm, 1.2x0.8m or 1200x800mm (a bare "
              "number is metres: 0.9x0.6), or round:D, a round top of diameter D such as "
              "round:120cm; each side 0.2 to 10 m [default: arrange 0.9x0.6 m; run and "
              "bench the scene's].", group="room", door=Door(metavar="WxD|round:D"))
    diners: int | None = setting(
        None, "Diners to seat at the target table, evenly along a rectangle's long sides or "
              "round a circle; a request (or task) for one setting is set for each "
              "[default: as the request or the scene says].", group="room", ge=1, le=12,
        door=Door(metavar="N"))

    capacity: int | None = setting(
        None, "Objects the robot carries per trip: 1 in the hand (the paper's); more ride on "
              "its tray, up to what the simulator's tray holds (4) [default: the scene's "
              "robot.capacity, 1 in the packaged scene].", group="sim", ge=1)

    # The arrangement (paper §III-A, §III-B)
    m: int = setting(
        25, "Configurations to sample (M).", group="llm", ge=1,
        door=Door(cli="--configurations", short="-m"))
    attempts: int = setting(
        3, "Template 1 prompts before keeping the largest consistent subset.", group="llm",
        ge=1)
    revisions: int | None = setting(
        None, "Rounds of the feedback loop per run: when the LLM's relations contradict "
              "each other, no placement on the table keeps them, or the robot cannot put an "
              "object where planned, the LLM is told what failed and why, and its revision "
              "is checked and used; 0 is the paper's way (a contradiction is answered by "
              "asking again blindly) [default: 2; 0 with the bundled SmolLM2-135M, whose "
              "revisions made two of the paper's tasks worse].", group="llm", ge=0, le=10,
        door=Door(metavar="N"))
    zero_shot: bool = setting(False, "Leave the paper's few-shot examples out.", group="llm")
    notes: str = setting("", "Text for Template 1's [notes] slot.", group="llm",
                         max_length=10_000)
    preferences: tuple[str, ...] = setting(
        (), "A relation you want, e.g. 'the dinner fork to the left of the dinner plate'; "
            "it wins over the LLM (repeatable).", group="llm",
        door=Door(cli="--prefer", metavar="SENTENCE", sweep="prefer"))
    preferences_file: str | None = setting(
        None, "YAML file `preferences: [sentences]`; those whose objects are all requested "
              "apply.", group="llm",
        door=Door(cli="--preferences", sweep="preferences", path="file"))
    examples: tuple[str, ...] = setting(
        (), "An example table setting (an arrangement JSON, or a run JSON's final) to learn "
            "preferences from, as `llm-grop learn` does: what holds in every example applies "
            "as --preferences does, and its relations say source learned (repeatable).",
        group="llm", door=Door(metavar="FILE", path="file"))
    guess: bool = setting(
        True, "Refuse a request the LLM would have to complete: objects it does not name "
              "(a meal, 'coffee'), or how many.", group="guess",
        door=Door(negate="--no-guess",
                  web='the "refuse the request" choice for the objects a request leaves out'))

    # The task-motion planner (paper §III-C)
    weight: float = setting(
        40.0, "GROP's utility weight w (seconds per unit of success probability).",
        group="plan", ge=0, allow_inf_nan=False, door=Door(cli="--weight"))
    fidelity_weight: float = setting(
        1.0, "Seconds of GROP's utility that one centimetre of infidelity costs (stated gaps "
             "missed, the setting's shift); 0 ignores fidelity.", group="plan", ge=0,
        allow_inf_nan=False)
    feasibility: str = setting(
        "auto", "The planner's feasibility profile: auto (the profile fitted to the "
                "simulator that executes: mujoco in 3D; in 2D the one --truth draws from, "
                "else default), default (assumed) or mujoco (fitted in 3D).", group="plan",
        min_length=1)

    # Execution
    simulator: str = setting(
        "kinematic2d", "The simulator that executes the plan (see `llm-grop plugins`).",
        group="sim", min_length=1)
    sim_options: Pairs = setting(
        (), "An option of the simulator, KEY=VALUE (a YAML value), as its Options declare "
            "them (`llm-grop plugins` lists them), e.g. timestep_s=0.002; repeatable.",
        group="sim", door=Door(cli="--sim-option", metavar="KEY=VALUE"))
    grasp: Grasp = setting(
        "fix", "--simulator mujoco: how the hand holds. fix: a weld that attaches only when "
               "both pads squeeze the object (Gazebo's grasp-fix); friction: contact "
               "friction alone (the README lists what it can carry).", group="sim")
    truth: str | None = setting(
        None, "--simulator kinematic2d: draw outcomes and durations from this feasibility "
              "profile (mujoco: what the 3D world was measured to do) [default: the 2D "
              "simulator's own, the default profile's curves].", group="sim",
        door=Door(metavar="PROFILE"))
    manip_attempts: int | None = setting(
        None, "Attempts per pick and per place of each object, re-grasps included "
              "[default: the method's: 20 for llm-grop, 10 for the others, as the authors "
              "ran them].", group="execution", ge=1)

    nav_attempts: int = setting(
        3, "Attempts per navigation goal before the next fallback standing position.",
        group="execution", ge=1)
    # The LLM
    llm: str = setting(
        "auto", "LLM backend: auto (a server named by --base-url or $OPENAI_BASE_URL, else "
                "one answering on 127.0.0.1's usual ports, else embedded), embedded, openai, "
                "replay, or a plugin's (see `llm-grop plugins`).", group="llm", min_length=1,
        door=Door(sweep="llm.backend"))
    model: str | None = setting(
        None, "Model name (openai) or GGUF path (embedded).", group="backend",
        door=Door(sweep="llm.model"))
    base_url: str | None = setting(
        None, "OpenAI-compatible endpoint (default: $OPENAI_BASE_URL).", group="backend",
        door=Door(sweep="llm.base_url"))
    replay: str | None = setting(
        None, "JSONL of recorded calls, for --llm replay.", group="backend",
        door=Door(sweep="llm.replay", path="file"))
    timeout_s: float = setting(
        60.0, "Seconds one LLM call may take, retries and their waits included.",
        group="backend", gt=0, allow_inf_nan=False, identity=False,
        door=Door(cli="--timeout"))
    max_answer_bytes: int = setting(
        1024 * 1024, "The largest LLM answer accepted, bytes (openai); a larger one is an "
                     "error.", group="backend", ge=1, identity=False)
    retries: int = setting(
        3, "Retries on transient LLM errors (connection, 429, 5xx).", group="backend", ge=0,
        identity=False)
    backend_options: Pairs = setting(
        (), "An option of the LLM backend, KEY=VALUE (a YAML value), as its Options declare "
            "them (`llm-grop plugins` lists them), e.g. structured_output=false; repeatable.",
        group="backend", door=Door(cli="--llm-option", sweep="llm.options",
                                   json="llm_options", metavar="KEY=VALUE"))
    temperature: float = setting(
        0.1, "Sampling temperature of every LLM call (the paper's 0.1).", group="llm",
        ge=0, le=2, door=Door(sweep="llm.temperature"))
    top_p: float = setting(
        1.0, "Nucleus sampling: keep the most likely tokens up to this probability.",
        group="llm", ge=0, le=1)
    max_tokens: int = setting(512, "Most tokens one LLM answer may have.", group="llm",
                              ge=1)
    frequency_penalty: float = setting(
        0.0, "Penalty on tokens by how often they appeared (OpenAI's meaning).", group="llm",
        ge=-2, le=2)
    presence_penalty: float = setting(
        0.0, "Penalty on tokens that appeared at all (OpenAI's meaning).", group="llm",
        ge=-2, le=2)
    cache: str | None = setting(
        None, "The shared LLM answer cache's directory (None: no cache); it changes no "
              "answer.", group="cache", identity=False,
        door=Door(cli="--cache-dir", path="dir",
                  cli_help="The shared LLM answer cache [default: $LLM_GROP_CACHE_DIR, "
                           "else ~/.cache/llm-grop/llm-calls]."))

    # Recordings of the episode (they change nothing in it)
    rerun: str | None = setting(
        None, "Write a Rerun recording of the episode here (.rrd; needs the [viz] extra): the "
              "room, the objects and the robot over simulated time, the plan, every attempt; "
              "`llm-grop view FILE.rrd` opens it.", group="record", identity=False,
        door=Door(path="file", metavar="FILE.rrd"))
    mcap: str | None = setting(
        None, "Write the episode as a ROS 2 bag here (.mcap; needs the [ros] extra): /tf, "
              "/plan/path, /plan/goals, /objects, /scan (MuJoCo) and /events in standard "
              "message types, for `ros2 bag play`, RViz or Foxglove.", group="record",
        identity=False, door=Door(path="file", metavar="FILE.mcap"))

    def __init__(self, **values: Any) -> None:
        """A record of ``values`` (field names), every value checked: the first problem is
        one :class:`BadInput` naming the field (``param``)."""
        unknown = [k for k in values if k not in type(self).model_fields]
        if unknown:
            raise BadInput(unknown_words(unknown[0], type(self).model_fields), param=unknown[0])
        try:
            super().__init__(**_coerced(values))
        except ValidationError as exc:
            raise problem(exc) from None

    @classmethod
    def make(cls, values: Mapping[str, Any] | None = None, **more: Any) -> RunSettings:
        """A record from ``values`` and ``more`` (field names), checked as the constructor
        checks them."""
        return cls(**(dict(values or {}) | more))

    def with_values(self, **changes: Any) -> RunSettings:
        """This record with ``changes`` (field names), checked as :meth:`make` checks."""
        if not changes:
            return self
        return type(self).make(self.model_dump() | changes)

    def identity(self) -> dict[str, Any]:
        """The fields that decide a run's result, by name (not the cache, deadlines or
        retries, which change no answer)."""
        return {name: value for name, value in self.model_dump(mode="json").items()
                if _extra(name).get("identity", True)}



def _coerced(given: dict[str, Any]) -> dict[str, Any]:
    """``given`` with paths and sequences in the record's types (``Path`` -> text, a list
    -> a tuple), so callers may pass what they hold."""
    out: dict[str, Any] = {}
    for name, value in given.items():
        if isinstance(value, list | tuple):
            value = tuple(os.fspath(v) if isinstance(v, os.PathLike) else v for v in value)
        elif isinstance(value, os.PathLike):
            value = os.fspath(value)
        out[name] = value
    return out


def _extra(name: str) -> dict[str, Any]:
    """The metadata written beside field ``name`` (group, identity, door)."""
    info = RunSettings.model_fields[name]
    return dict(info.json_schema_extra or {})  # type: ignore[arg-type]


#: The record as nothing changes it: every default, for components to read theirs from.
DEFAULTS = RunSettings()

