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


def create_simulator(name: str = DEFAULT_SIMULATOR, *, grasp: str = "fix",
                     truth: str | None = None) -> Simulator:
    """A new simulator by name; :class:`BadInput` for an unknown or malformed one. A grasp
    other than MuJoCo's default ``fix`` needs ``mujoco``; a ``truth`` (a packaged profile
    the 2D draws follow) needs ``kinematic2d``."""
    if truth is not None:
        if SIMULATORS.key(name) != "kinematic2d":
            raise BadInput(f"needs the kinematic2d simulator (got {name!r})", param="truth",
                           value=truth)
        from llm_grop.simulation.kinematic2d import Kinematic2D, Kinematic2DOptions
        from llm_grop.simulation.outcomes import ParametricOutcomes

        return Kinematic2D(Kinematic2DOptions(outcomes=ParametricOutcomes.from_profile(truth)))
    if grasp != "fix":
        if SIMULATORS.key(name) != "mujoco":
            raise BadInput(f"needs the mujoco simulator (got {name!r})", param="grasp",
                           value=grasp)
        from llm_grop.simulation.mujoco.simulator import MujocoOptions, MujocoSimulator

        return MujocoSimulator(MujocoOptions(grasp=grasp))  # type: ignore[arg-type]
    sim: Simulator = SIMULATORS.create(name)
    key = SIMULATORS.key(name)
    if sim.name != key:
        raise BadInput(f"{SIMULATORS.origin(key)}: simulator {key!r} calls itself "
                       f"{sim.name!r}; the two must agree", param="simulator")
    return sim
