"""The explicit registry of simulators (see :mod:`llm_grop.simulation.base`)."""

from __future__ import annotations

from collections.abc import Callable

from llm_grop.errors import BadInput
from llm_grop.simulation.base import Simulator
from llm_grop.simulation.kinematic2d import Kinematic2D

_REGISTRY: dict[str, Callable[[], Simulator]] = {"kinematic2d": Kinematic2D}


def register_simulator(name: str, factory: Callable[[], Simulator]) -> None:
    """Make a simulator available under ``name``."""
    _REGISTRY[name] = factory


def available_simulators() -> list[str]:
    """Registered simulator names, sorted."""
    return sorted(_REGISTRY)


def create_simulator(name: str) -> Simulator:
    """A new simulator by name; :class:`BadInput` for an unknown one."""
    try:
        return _REGISTRY[name]()
    except KeyError:
        raise BadInput(f"--simulator: unknown simulator {name!r} "
                       f"(available: {', '.join(available_simulators())})") from None
