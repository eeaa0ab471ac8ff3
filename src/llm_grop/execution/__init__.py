"""The executive: runs a task-motion plan on any simulator, one attempt at a time.

It holds the whole execution policy in one place, as the task script above move_base and
the arm's services did in the authors' system: how often to retry navigation and
manipulation, which fallback standing position to try next, when to re-grasp an object
that came to rest out of place, and when to give up. Simulators only offer primitives
(:class:`~llm_grop.simulation.base.Session`). Success is a physical state, read from the
session after the physics settles (:mod:`llm_grop.execution.judge`).
"""

from llm_grop.execution.executive import execute, execute_plan
from llm_grop.execution.policy import ExecutionPolicy

__all__ = ["ExecutionPolicy", "execute", "execute_plan"]
