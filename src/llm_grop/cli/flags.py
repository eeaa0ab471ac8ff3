"""How the command line words errors: the Python API's parameter names become its flags.

Errors raised through the API name the API's parameters (``method: unknown method
'nope'``, ``out='runs/x': not empty``); here they become ``--method: ...`` and
``--out runs/x: ...``. A parameter not listed is spelled as a flag of the same name
(``max_failed`` -> ``--max-failed``).
"""

from __future__ import annotations

from llm_grop.errors import LLMGropError

#: API parameter -> the flag (or argument) that gives it, where the two differ.
FLAGS: dict[str, str] = {
    "request": "request",
    "planner.fidelity_w_s_per_cm": "--fidelity-weight",
    "planner.w": "--weight",
    "options.preferences": "--prefer",
    "video_path": "--video",
}

#: API phrases inside messages -> their command-line words.
PHRASES: dict[str, str] = {
    "guess=False": "--no-guess",
    "max_answer_bytes": "--max-answer-bytes",
    "chairs=N": "--chairs N",
}


def flag(param: str) -> str:
    """The flag that gives the API parameter ``param``."""
    return FLAGS.get(param, "--" + param.replace("_", "-"))


def cli_words(text: str) -> str:
    """``text`` (a message or a warning of the API) with the command line's words for
    the API's phrases in it (:data:`PHRASES`)."""
    for api, words in PHRASES.items():
        text = text.replace(api, words)
    return text


def reworded(exc: LLMGropError) -> str:
    """``exc``'s one-line message in the command line's words."""
    text = cli_words(getattr(exc, "detail", None) or str(exc))
    param = getattr(exc, "param", None)
    if param is None:
        return text
    name = flag(param)
    if exc.value is None:
        return f"{name}: {text}"
    value = str(exc.value)
    return f"{name} {value if value and ' ' not in value else repr(value)}: {text}"
