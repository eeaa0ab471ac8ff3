"""The registry of simulators (see :mod:`llm_grop.plugins`): entry point group
``llm_grop.simulators``; an entry is a factory ``() -> Simulator``."""

from __future__ import annotations

from collections.abc import Callable

from llm_grop.errors import BadInput
from llm_grop.plugins import Registry
from llm_grop.simulation.base import Simulator

Factory = Callable[[], Simulator]

#: The simulator ``run`` and ``bench`` use unless told otherwise.
DEFAULT_SIMULATOR = "kinematic2d"


SIMULATORS: Registry[Factory] = Registry(
    group="llm_grop.simulators", kind="simulator", flag="--simulator", module=__name__,
    builtins={"kinematic2d": "llm_grop.simulation.kinematic2d:Kinematic2D",
              "mujoco": "llm_grop.simulation.mujoco.simulator:MujocoSimulator"},
    factory="() -> Simulator", product=("name", "session"))


def register_simulator(name: str, factory: Factory) -> None:
    """Make a simulator available as ``--simulator NAME`` in this process (and the bench's
    workers)."""
    SIMULATORS.register(name, factory)


def available_simulators() -> list[str]:
    """Names of every available simulator."""
    return SIMULATORS.names()


def create_simulator(name: str = DEFAULT_SIMULATOR) -> Simulator:
    """A new simulator by name; :class:`BadInput` for an unknown or malformed one."""
    sim: Simulator = SIMULATORS.create(name)
    key = SIMULATORS.key(name)
    if sim.name != key:
        raise BadInput(f"--simulator: {SIMULATORS.origin(key)}: simulator {key!r} calls itself "
                       f"{sim.name!r}; the two must agree")
    return sim
