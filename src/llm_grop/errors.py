"""Errors that reach the user, each mapped to one of the contract's exit codes.

This module imports nothing from the package, so every layer may raise these.
"""

from __future__ import annotations

#: Exit status of an internal error (a bug in llm-grop): sysexits' ``EX_SOFTWARE``, apart
#: from every status an error of this module gives.
INTERNAL_ERROR_EXIT = 70


class LLMGropError(Exception):
    """Base class: an error with a one-line message meant for the user.

    ``param`` names the Python API's parameter at fault (``"method"``) and ``value`` what
    was given for it, when that helps: the message then reads ``method: unknown method
    'nope' ...`` or ``out='runs/x': ...``, and the command line rewords the name as its
    flag (``--method``, ``--out runs/x``). ``detail`` is the message without the name.
    ``mentions`` names the settings the message mentions in Python's words
    (``guess=False``), which each front door spells its own way (``--no-guess``).
    """

    exit_code = 2

    def __init__(self, message: str = "", *, param: str | None = None,
                 value: object = None, mentions: tuple[str, ...] = ()) -> None:
        self.param, self.value, self.detail = param, value, message
        self.mentions = tuple(mentions)
        shown = value if isinstance(value, int | float) else str(value)
        named = param if value is None else f"{param}={shown!r}"
        super().__init__(message if param is None else f"{named}: {message}")

    def __reduce__(self) -> tuple[object, ...]:
        # Worker processes send errors back pickled; the parameter must survive the trip
        # for the command line to name its flag.
        if self.param is None and not self.mentions:
            return super().__reduce__()
        return (_rebuilt, (type(self), self.detail, self.param, self.value, self.mentions))


def _rebuilt(cls: type[LLMGropError], detail: str, param: str | None, value: object,
             mentions: tuple[str, ...] = ()) -> LLMGropError:
    """A pickled error with its parameter and mentions, made again."""
    return cls(detail, param=param, value=value, mentions=mentions)


class BadInput(LLMGropError, ValueError):
    """Bad input: an unknown object, a malformed file, a bad argument (exit 2). It is a
    :class:`ValueError`, so ``except ValueError`` catches it too. For "nothing feasible"
    (no arrangement or plan exists) catch :class:`Infeasible`; for an LLM service that did
    not answer this time, :class:`LLMTransient`.
    """

    exit_code = 2


class UnknownObject(BadInput):
    """A requested object is in no catalog; ``suggestions`` holds the closest names."""

    def __init__(self, name: str, suggestions: list[str], where: str = "request") -> None:
        self.name = name
        self.suggestions = suggestions
        self.where = where
        hint = f"; did you mean {', '.join(repr(s) for s in suggestions)}?" if suggestions else ""
        super().__init__(f"{where}: unknown object {name!r}{hint}")

    def __reduce__(self) -> tuple[object, ...]:
        return (type(self), (self.name, self.suggestions, self.where))


class CatalogError(BadInput):
    """A catalog file is malformed; the message names the file and the field."""


class LLMError(BadInput):
    """The LLM could not be used as configured: a wrong key, model, file or replay file,
    or answers that never give a usable reading (bad input, exit 2)."""


class LLMUnavailable(LLMError):
    """The LLM endpoint or model cannot be used as configured: a refused key, an unknown
    model, a missing model file (bad input, exit 2). An endpoint that did not answer this
    time is :class:`LLMTransient`."""


class LLMAnswerUnusable(LLMError):
    """The LLM answered, but nothing usable: an answer over ``max_answer_bytes``, JSON
    with no reply in it, or answers with no readable relation after every attempt. A
    single run stops on it (bad input, exit 2); a bench keeps the trial as ``llm-failed``
    and goes on, since another answer may be usable."""


class LLMTransient(LLMGropError):
    """The LLM service did not answer this time (unreachable, over the deadline, busy,
    failing with 5xx, or a garbled answer) where asking again later may succeed (exit 3).

    It is not bad input, so neither ``except ValueError`` nor ``except LLMError`` catches
    it; a wrong key, model or configuration is :class:`LLMUnavailable` and stays so."""

    exit_code = 3


class ReplayMissing(LLMError):
    """A replay file holds no response for a prompt."""


class Infeasible(LLMGropError):
    """Nothing feasible exists: no arrangement or plan satisfies the constraints (exit 1)."""

    exit_code = 1


class NoArrangement(Infeasible):
    """The sampler found too few configurations that keep the relations: ``objects`` are
    the objects where configurations got stuck most, ``why`` the commonest rejection there
    (``"mug leaves the 0.45 x 0.3 m table"``), for the feedback loop to tell the LLM."""

    def __init__(self, message: str = "", objects: tuple[str, ...] = (), why: str = ""
                 ) -> None:
        super().__init__(message)
        self.objects, self.why = tuple(objects), why

    def __reduce__(self) -> tuple[object, ...]:
        return (type(self), (self.detail, self.objects, self.why))


class OutOfReach(NoArrangement):
    """Every configuration sampled puts an object where the planner believes the robot
    cannot place it from anywhere it can stand: ``objects`` names it, ``why`` says how far
    it is from the nearest such place."""


def interrupted(exc: BaseException) -> bool:
    """Whether ``exc`` is, or was caused by, an interrupt: an extension module that Ctrl-C
    stops while it initialises reports ``ImportError: initialization failed`` from the
    ``KeyboardInterrupt``."""
    seen: set[int] = set()
    cause: BaseException | None = exc
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, KeyboardInterrupt):
            return True
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    return False
