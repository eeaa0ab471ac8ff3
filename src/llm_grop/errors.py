"""Errors that reach the user, each mapped to one of the contract's exit codes.

This module imports nothing from the package, so every layer may raise these.
"""

from __future__ import annotations


class LLMGropError(Exception):
    """Base class: an error with a one-line message meant for the user."""

    exit_code = 2


class BadInput(LLMGropError, ValueError):
    """Bad input: an unknown object, a malformed file, a bad flag (exit 2). It is a
    :class:`ValueError`, so ``except ValueError`` catches it too. For "nothing feasible"
    (no arrangement or plan exists) catch :class:`Infeasible`."""

    exit_code = 2


class UnknownObject(BadInput):
    """A requested object is in no catalog; ``suggestions`` holds the closest names."""

    def __init__(self, name: str, suggestions: list[str], where: str = "request") -> None:
        self.name = name
        self.suggestions = suggestions
        hint = f"; did you mean {', '.join(repr(s) for s in suggestions)}?" if suggestions else ""
        super().__init__(f"{where}: unknown object {name!r}{hint}")


class CatalogError(BadInput):
    """A catalog file is malformed; the message names the file and the field."""


class LLMError(BadInput):
    """The LLM could not be used: unreachable, misconfigured, or never usable."""


class LLMUnavailable(LLMError):
    """The LLM endpoint or model could not be reached or loaded."""


class LLMTransient(LLMUnavailable):
    """The LLM did not answer this time (unreachable, over the deadline, busy, failing
    with 5xx, or a garbled answer) where asking again later may succeed; a wrong key,
    model or configuration is :class:`LLMUnavailable` and stays so."""


class ReplayMissing(LLMError):
    """A replay file holds no response for a prompt."""


class Infeasible(LLMGropError):
    """Nothing feasible exists: no arrangement or plan satisfies the constraints (exit 1)."""

    exit_code = 1
