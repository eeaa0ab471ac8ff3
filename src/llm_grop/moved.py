"""Modules that moved, and their old import paths, which keep working with a warning.

``import llm_grop.world.contract`` (or ``from llm_grop.world.contract import RunDoc``)
gives the very module :mod:`llm_grop.contract.models` and warns with a
:class:`DeprecationWarning` naming the new path. The old path is an alias made by a finder
on :data:`sys.meta_path`, not a module of its own, so the package that lost the module
(``world``) does not import the one that gained it: the layers stay as they are.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import warnings
from collections.abc import Sequence
from types import ModuleType

#: Old dotted path -> where the module lives now.
MOVED: dict[str, str] = {
    # Wire formats: issue 36, part 3.
    "llm_grop.world.contract": "llm_grop.contract.models",
    "llm_grop.world.plan_doc": "llm_grop.contract.plan_doc",
    "llm_grop.world.run_json": "llm_grop.contract.run_json",
    "llm_grop.world.schemas": "llm_grop.contract.schemas",
    "llm_grop.world.serialize": "llm_grop.contract.serialize",
    # File readers and writers.
    "llm_grop.world.jsonio": "llm_grop.files.jsonio",
    "llm_grop.world.profiles": "llm_grop.files.profiles",
    "llm_grop.world.scene_file": "llm_grop.files.scene_file",
    # Below the world, whose catalog and task files read through it.
    "llm_grop.world.datafile": "llm_grop.datafile",
}


class _Alias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds an old path of :data:`MOVED` and loads it as the module at its new path."""

    def find_spec(self, fullname: str, path: Sequence[str] | None,
                  target: ModuleType | None = None) -> importlib.machinery.ModuleSpec | None:
        if fullname not in MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> None:
        return None  # a blank module, which exec_module swaps for the moved one

    def exec_module(self, module: ModuleType) -> None:
        old = module.__name__
        new = MOVED[old]
        # stacklevel 2 is the importing line: warnings skips importlib's own frames.
        warnings.warn(f"{old} has moved to {new}; import it from there", DeprecationWarning,
                      stacklevel=2)
        # The import system returns what sys.modules holds under the old name once this
        # returns, so the old name gives the moved module itself (same objects, and its
        # __spec__ untouched), not a copy.
        sys.modules[old] = importlib.import_module(new)


def install() -> None:
    """Puts the finder of old paths first on :data:`sys.meta_path` (once): a stale file
    left at an old path by an upgrade cannot shadow the moved module."""
    if not any(isinstance(f, _Alias) for f in sys.meta_path):
        sys.meta_path.insert(0, _Alias())
