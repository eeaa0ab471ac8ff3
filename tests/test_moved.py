"""Modules that moved out of ``world`` (issue 36, part 3) still import from their old
paths: the very module at its new path, with a DeprecationWarning naming that path."""

from __future__ import annotations

import importlib
import subprocess
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

import pytest

from llm_grop.moved import MOVED

SRC = Path(__file__).resolve().parents[1] / "src"


@pytest.fixture
def forgotten() -> Iterator[None]:
    """No old path imported yet; afterwards, none left behind in ``sys.modules`` or as an
    attribute of its old package."""
    saved = {old: sys.modules.pop(old) for old in MOVED if old in sys.modules}
    yield
    for old in MOVED:
        sys.modules.pop(old, None)
        parent, _, child = old.rpartition(".")
        vars(sys.modules[parent]).pop(child, None)
    sys.modules.update(saved)


@pytest.mark.parametrize("old", sorted(MOVED))
def test_an_old_path_gives_the_moved_module_and_warns(old: str, forgotten: None) -> None:
    new = MOVED[old]
    with pytest.warns(DeprecationWarning, match=f"^{old} has moved to {new}; ") as caught:
        module = importlib.import_module(old)
    assert module is importlib.import_module(new) is sys.modules[old]
    assert module.__name__ == module.__spec__.name == new  # the moved module, untouched
    assert not (SRC / f"{old.replace('.', '/')}.py").exists()
    assert len(caught) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert importlib.import_module(old) is module  # warned once, as an import is done once


def test_names_import_from_their_old_paths(forgotten: None) -> None:
    from llm_grop.contract import models, run_json, serialize
    from llm_grop.files import scene_file

    with pytest.warns(DeprecationWarning, match="llm_grop.contract.models") as caught:
        from llm_grop.world.contract import RunDoc
    assert RunDoc is models.RunDoc
    assert caught[0].filename == __file__  # the warning points at the importing line
    with pytest.warns(DeprecationWarning):
        from llm_grop.world import serialize as old_serialize
    assert old_serialize.arrangement_to_dict is serialize.arrangement_to_dict
    with pytest.warns(DeprecationWarning):
        import llm_grop.world.run_json
        import llm_grop.world.scene_file
    assert llm_grop.world.scene_file.load_scene is scene_file.load_scene
    assert llm_grop.world.run_json.run_to_dict is run_json.run_to_dict


def test_the_new_paths_import_without_a_warning() -> None:
    code = ("import importlib, sys; from llm_grop.moved import MOVED\n"
            "for new in MOVED.values(): importlib.import_module(new)\n"
            "import llm_grop.world\n"
            "print(sorted(m for m in sys.modules if m in MOVED))\n")
    done = subprocess.run([sys.executable, "-W", "error", "-c", code], capture_output=True,
                          text=True, check=True)
    assert done.stdout.strip() == "[]"


def test_an_unknown_module_of_world_is_still_an_import_error() -> None:
    with pytest.raises(ModuleNotFoundError, match="llm_grop.world.nope"):
        importlib.import_module("llm_grop.world.nope")
