"""The registry of simulators (see :mod:`llm_grop.plugins`): entry point group
``llm_grop.simulators``; an entry is a :class:`~llm_grop.simulation.base.Simulator`
subclass, which declares its ``Options`` and what it can do."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from llm_grop.errors import BadInput, LLMGropError
from llm_grop.plugins import Registry
from llm_grop.settings import DEFAULTS
from llm_grop.simulation.base import Simulator, option_names, options_of

#: The simulator ``run`` and ``bench`` use unless told otherwise.
DEFAULT_SIMULATOR = DEFAULTS.simulator


def _check(name: str, obj: Any, origin: str) -> None:
    if not (isinstance(obj, type) and issubclass(obj, Simulator)):
        raise BadInput(f"{origin}: simulator {name!r} is not a subclass of "
                       "llm_grop.simulation.base.Simulator (one that declares its name, "
                       "Options and what it can do)", param="simulator")
    if str(obj.name).strip().lower() != name:
        raise BadInput(f"{origin}: simulator {name!r} calls itself {obj.name!r}; the two "
                       "must agree", param="simulator")


SIMULATORS: Registry[type[Simulator]] = Registry(
    group="llm_grop.simulators", kind="simulator", flag="--simulator", module=__name__,
    builtins={"kinematic2d": "llm_grop.simulation.kinematic2d:Kinematic2D",
              "mujoco": "llm_grop.simulation.mujoco.simulator:MujocoSimulator"},
    check=_check)


def register_simulator(name: str, simulator: type[Simulator]) -> None:
    """Make a simulator class available as ``--simulator NAME`` in this process (and the
    bench's workers)."""
    SIMULATORS.register(name, simulator)


def available_simulators() -> list[str]:
    """Names of every available simulator."""
    return SIMULATORS.names()


def simulator_class(name: str) -> type[Simulator]:
    """The simulator class registered as ``name``: what it declares it can do, before
    one is made."""
    return SIMULATORS.get(SIMULATORS.key(name))


#: Settings of the record that are one simulator's option, and that simulator.
_SHORTHANDS = {"grasp": (DEFAULTS.grasp, "mujoco"), "truth": (DEFAULTS.truth, "kinematic2d")}


def create_simulator(name: str = DEFAULT_SIMULATOR, options: Mapping[str, Any] | None = None,
                     *, grasp: str = DEFAULTS.grasp, truth: str | None = DEFAULTS.truth
                     ) -> Simulator:
    """A new simulator by name, built with ``options`` (its declared ``Options`` by name,
    checked); :class:`BadInput` for an unknown name or option. ``grasp`` (MuJoCo's hand)
    and ``truth`` (the profile the 2D draws follow) are options of one simulator each,
    given apart as the settings record holds them."""
    key = SIMULATORS.key(name)
    cls = SIMULATORS.get(key)
    values = dict(options or {})
    for option, value in (("grasp", grasp), ("truth", truth)):
        default, owner = _SHORTHANDS[option]
        if value == default:
            continue
        if option not in option_names(cls):
            raise BadInput(f"needs the {owner} simulator (got {name!r})", param=option,
                           value=value)
        values[option] = value
    made = options_of(cls, values)
    origin = SIMULATORS.origin(key)
    try:
        sim = cls(made)  # type: ignore[call-arg]
    except LLMGropError:
        raise
    except Exception as exc:
        if origin == "llm-grop":
            raise
        raise BadInput(f"{origin}: simulator {key!r} failed to start: "
                       f"{type(exc).__name__}: {exc}", param="simulator") from None
    return sim
