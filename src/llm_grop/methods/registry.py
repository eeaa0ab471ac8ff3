"""The registry of methods (see :mod:`llm_grop.plugins`): entry point group
``llm_grop.methods``; an entry is a :class:`~llm_grop.methods.base.Method` whose ``name``
is the name it is registered under."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from llm_grop.errors import BadInput
from llm_grop.execution.policy import LLM_GROP_MANIP_ATTEMPTS
from llm_grop.methods.base import ComposedMethod, Method
from llm_grop.plugins import Registry
from llm_grop.settings.declared import declared_options

#: The paper's four methods (§IV).
TPRA = ComposedMethod("tpra", "task planning with random arrangement and standing positions",
                      uses_llm=False, standing="uniform", best_of_all=False)
LATP = ComposedMethod("latp", "LLM arrangement with task planning, random standing positions",
                      uses_llm=True, standing="uniform", best_of_all=False)
GROP = ComposedMethod("grop", "random arrangement, utility-optimal task-motion plan",
                      uses_llm=False, standing="utility", best_of_all=True)
LLM_GROP = ComposedMethod("llm-grop", "LLM arrangement, utility-optimal task-motion plan",
                          uses_llm=True, standing="utility", best_of_all=True,
                          manip_attempts=LLM_GROP_MANIP_ATTEMPTS)

def _check(name: str, obj: Any, origin: str) -> None:
    if isinstance(obj, type) or not isinstance(obj, Method):
        raise BadInput(f"{origin}: {name!r} is not a method instance (it needs a name, a "
                       "description, an arrangement, a standing_choice, manip_attempts, "
                       "Options and with_options; "
                       "see llm_grop.methods.base.Method)", param="method")
    if str(obj.name).strip().lower() != name:
        raise BadInput(f"{origin}: method registered as {name!r} is named "
                       f"{obj.name!r}; the two must agree", param="method")


METHODS: Registry[Method] = Registry(
    group="llm_grop.methods", kind="method", flag="--method", module=__name__,
    builtins={m.name: f"{__name__}:{var}" for m, var in (
        (TPRA, "TPRA"), (LATP, "LATP"), (GROP, "GROP"), (LLM_GROP, "LLM_GROP"))},
    check=_check)


def register_method(method: Method) -> None:
    """Make ``method`` available under its name, in this process (and the bench's workers)."""
    METHODS.register(method.name, method)


def available_methods() -> list[str]:
    """Every available method name: the paper's four first."""
    return METHODS.names()


def get_method(name: str, options: Mapping[str, Any] | None = None) -> Method:
    """A method by name, with ``options`` (its declared ``Options`` by name, checked:
    :class:`BadInput` naming ``method_options.KEY``); :class:`BadInput` for an unknown
    name."""
    method = METHODS.get(name)
    if not options:
        return method
    made = declared_options(method.Options, options, owner=f"method {method.name!r}",
                            param="method_options")
    return method.with_options(made)
