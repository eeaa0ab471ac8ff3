"""The explicit registry of methods."""

from __future__ import annotations

from llm_grop.errors import BadInput
from llm_grop.methods.base import ComposedMethod, Method

_METHODS: dict[str, Method] = {
    m.name: m for m in (
        ComposedMethod("tpra", "task planning with random arrangement and standing positions",
                       uses_llm=False, standing="uniform", best_of_all=False),
        ComposedMethod("latp", "LLM arrangement with task planning, random standing positions",
                       uses_llm=True, standing="uniform", best_of_all=False),
        ComposedMethod("grop", "random arrangement, utility-optimal task-motion plan",
                       uses_llm=False, standing="utility", best_of_all=True),
        ComposedMethod("llm-grop", "LLM arrangement, utility-optimal task-motion plan",
                       uses_llm=True, standing="utility", best_of_all=True),
    )
}


def register_method(method: Method) -> None:
    """Make ``method`` available under its name."""
    _METHODS[method.name] = method


def available_methods() -> list[str]:
    """Registered method names, in registration order."""
    return list(_METHODS)


def get_method(name: str) -> Method:
    """A method by name; :class:`BadInput` for an unknown one."""
    try:
        return _METHODS[name.strip().lower()]
    except KeyError:
        raise BadInput(f"--method: unknown method {name!r} "
                       f"(available: {', '.join(available_methods())})") from None
