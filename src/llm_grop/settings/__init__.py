"""The one settings record of a run: every option that shapes it, written once.

:class:`RunSettings` holds what a run is given besides its request: the paper's task or a
request's objects, the method, the scene, chairs and table, the seed, the arrangement's
options (M, Template 1's prompts, preferences), the planner's weights and belief, the
simulator, the LLM and its sampling, the executive's attempt counts and the LLM cache.
Each field's default, unit, bounds and help text are written here and nowhere else; the
front doors are views of it:

- the Python API (:func:`llm_grop.api.run` and friends) takes a record, or keyword
  overrides named as its fields (``m=10``);
- the command line's flags are generated from the fields (:mod:`llm_grop.cli.settings`);
- a sweep file's keys and the service's JSON bodies name the same fields;
- a bench's ``experiment.json`` and trial rows use the same names.

A bad value is one :class:`~llm_grop.errors.BadInput` naming the field (``param``); each
front door words that name its own way through :func:`label` (``--configurations``,
``m:`` in a sweep file, ``"m"`` in JSON, ``m=`` in Python), from the field's metadata
here, not from a table kept by hand.

This module imports nothing from the package but :mod:`llm_grop.errors`, so every layer
may read its defaults (:data:`DEFAULTS`).
"""

from __future__ import annotations

from llm_grop.settings.doors import (
    door,
    extra,
    fields,
    flag,
    help_text,
    in_words,
    label,
    words,
)
from llm_grop.settings.reasons import first_reason
from llm_grop.settings.record import (
    DEFAULTS,
    MAX_SEED,
    Door,
    Interface,
    RunSettings,
    setting,
)

__all__ = ["DEFAULTS", "MAX_SEED", "Door", "Interface", "RunSettings", "door", "extra",
           "fields", "first_reason", "flag", "help_text", "in_words", "label", "setting",
           "words"]
