"""The plugin mechanism (:mod:`llm_grop.plugins`) with real distributions and processes.

* A plugin package is built and installed with pip (offline, into a target directory) and
  its method runs in ``llm-grop bench`` with spawned workers, which find the entry point
  again by themselves.
* A method registered at run time reaches the bench's spawned workers; one that cannot be
  pickled is refused with a clear message.
* A plugin that fails to load, or whose method is misnamed, gives a one-line exit-2 error.
* A plugin may not take a name llm-grop ships: the built-in stays.

Installed entry points are found once per process, so everything that needs a plugin on
the path runs in a subprocess with ``PYTHONPATH`` pointing at a site directory. Those sites
are either built by pip or written by hand (a ``*.dist-info`` directory with ``METADATA``
and ``entry_points.txt``, which :mod:`importlib.metadata` discovers like any other).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from llm_grop import plugins
from llm_grop.contract.models import TrialRow
from llm_grop.errors import BadInput
from llm_grop.methods.base import ComposedMethod, Method
from llm_grop.methods.registry import METHODS, register_method

#: Seconds any one subprocess may take (a small bench takes a few).
TIMEOUT_S = 300

DEMO_PYPROJECT = """\
[build-system]
requires = ["setuptools"]
build-backend = "setuptools.build_meta"

[project]
name = "llm-grop-demo"
version = "0.1"
description = "A demo llm-grop plugin: one method"

[project.entry-points."llm_grop.methods"]
shuffled = "llm_grop_demo:SHUFFLED"

[tool.setuptools]
py-modules = ["llm_grop_demo"]
"""

DEMO_MODULE = """\
from llm_grop.methods.base import ComposedMethod

SHUFFLED = ComposedMethod("shuffled", "random arrangement, uniform standing, best of all",
                          uses_llm=False, standing="uniform", best_of_all=True)
"""


def _env(*paths: Path) -> dict[str, str]:
    """This process's environment with ``paths`` put first on ``PYTHONPATH`` (and no
    ``LLM_GROP_DEBUG``, which would turn one-line errors into tracebacks)."""
    env = {k: v for k, v in os.environ.items() if k != "LLM_GROP_DEBUG"}
    parts = [str(p) for p in paths]
    if env.get("PYTHONPATH"):
        parts.append(env["PYTHONPATH"])
    if parts:
        env["PYTHONPATH"] = os.pathsep.join(parts)
    return env


def _llm_grop(args: list[str], cwd: Path, *paths: Path) -> subprocess.CompletedProcess[str]:
    """``llm-grop ARGS`` in a new process with ``paths`` on ``PYTHONPATH``."""
    return subprocess.run([sys.executable, "-m", "llm_grop", *args], cwd=cwd,
                          env=_env(*paths), capture_output=True, text=True,
                          timeout=TIMEOUT_S, check=False)


def _python(script: str, cwd: Path, *paths: Path) -> subprocess.CompletedProcess[str]:
    """Run ``script`` (a file in ``cwd``, so spawned workers can import its main module)
    with ``paths`` on ``PYTHONPATH``; it must succeed."""
    path = cwd / "script.py"
    path.write_text(textwrap.dedent(script), encoding="utf-8")
    proc = subprocess.run([sys.executable, str(path), str(cwd)], cwd=cwd, env=_env(*paths),
                          capture_output=True, text=True, timeout=TIMEOUT_S, check=False)
    assert proc.returncode == 0, proc.stderr
    return proc


def _one_line_error(proc: subprocess.CompletedProcess[str]) -> str:
    """The single line a failed command printed on stderr; it exited 2, no traceback."""
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    assert "Traceback" not in proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, proc.stderr
    return lines[0]


def _rows(out: Path) -> list[TrialRow]:
    """Every line of ``out/trials.jsonl``, validated as the contract's trial row."""
    lines = (out / "trials.jsonl").read_text(encoding="utf-8").splitlines()
    return [TrialRow.model_validate(json.loads(line)) for line in lines]


def _write_dist_info(site: Path, dist: str, entry_points: str,
                     modules: dict[str, str]) -> Path:
    """An installed distribution written by hand: ``dist`` 0.1 with ``entry_points``
    (the ``entry_points.txt`` text) and top-level ``modules`` (name -> source)."""
    info = site / f"{dist.replace('-', '_')}-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 0.1\n",
                                   encoding="utf-8")
    (info / "entry_points.txt").write_text(textwrap.dedent(entry_points), encoding="utf-8")
    for name, source in modules.items():
        (site / f"{name}.py").write_text(textwrap.dedent(source), encoding="utf-8")
    return site


@pytest.fixture(scope="module")
def demo_site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A site directory holding the ``llm-grop-demo`` plugin, built and installed by pip
    from its source offline (once for this module)."""
    root = tmp_path_factory.mktemp("demo-plugin")
    pkg, site = root / "llm-grop-demo", root / "site"
    pkg.mkdir()
    (pkg / "pyproject.toml").write_text(DEMO_PYPROJECT, encoding="utf-8")
    (pkg / "llm_grop_demo.py").write_text(DEMO_MODULE, encoding="utf-8")
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-index", "--no-deps",
         "--no-build-isolation", "--no-cache-dir", "--disable-pip-version-check",
         "--target", str(site), str(pkg)],
        cwd=root, capture_output=True, text=True, timeout=TIMEOUT_S, check=False)
    assert proc.returncode == 0, f"pip could not build the demo plugin:\n{proc.stderr}"
    assert (site / "llm_grop_demo.py").is_file()
    assert list(site.glob("llm_grop_demo-0.1.dist-info/entry_points.txt"))
    return site


@pytest.fixture(scope="module")
def faulty_site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A site directory with one plugin distribution, ``llm-grop-faulty``, whose entries
    are broken in every way but one (``fine``)."""
    return _write_dist_info(
        tmp_path_factory.mktemp("faulty-plugin"), "llm-grop-faulty",
        """\
        [llm_grop.methods]
        fine = llm_grop_faulty:FINE
        broken = llm_grop_faulty_boom:METHOD
        absent = llm_grop_faulty:NO_SUCH
        misnamed = llm_grop_faulty:MISNAMED
        classy = llm_grop_faulty:ComposedMethod

        [llm_grop.simulators]
        broken-sim = llm_grop_faulty_absent:SIMULATOR
        failing-sim = llm_grop_faulty:FailingSimulator
        function-sim = llm_grop_faulty:simulator_function

        [llm_grop.llm_backends]
        not-an-llm = llm_grop_faulty:NotLLM
        """,
        {"llm_grop_faulty": """\
            from llm_grop.methods.base import ComposedMethod

            FINE = ComposedMethod("fine", "a working method", uses_llm=False,
                                  standing="uniform", best_of_all=False)
            MISNAMED = ComposedMethod("other", "named unlike its entry point",
                                      uses_llm=False, standing="uniform", best_of_all=False)


            from llm_grop.simulation.kinematic2d import Kinematic2D


            class FailingSimulator(Kinematic2D):
                name = "failing-sim"

                def __init__(self, options=None):
                    raise RuntimeError("no physics engine here")


            def simulator_function():
                return Kinematic2D()


            class NotLLM:
                def __init__(self, options):
                    self.options = options
            """,
         "llm_grop_faulty_boom": """\
            raise RuntimeError("demo plugin cannot start")
            """})


# --- an installed plugin, built by pip ----------------------------------------------------


def test_installed_plugin_method_runs_in_bench_workers(demo_site: Path, tmp_path: Path) -> None:
    out = tmp_path / "bench"
    proc = _llm_grop(["bench", "--tasks", "1", "--trials", "2", "--methods", "shuffled,grop",
                      "--workers", "2", "--out", str(out), "--no-images", "-q"],
                     tmp_path, demo_site)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    rows = _rows(out)
    assert sorted((r.method, r.task, r.trial) for r in rows) == [
        ("grop", 1, 0), ("grop", 1, 1), ("shuffled", 1, 0), ("shuffled", 1, 1)]
    # Trial k uses seed k for every method: the comparison is paired.
    assert all(r.seed == r.trial for r in rows)
    assert (out / "summary.json").is_file()


def test_installed_plugin_is_listed_after_the_builtins(demo_site: Path,
                                                      tmp_path: Path) -> None:
    proc = _python("""\
        import json
        from llm_grop.methods.registry import METHODS, available_methods, get_method

        method = get_method("Shuffled ")
        print(json.dumps({"names": available_methods(), "origin": METHODS.origin("shuffled"),
                          "name": method.name, "standing": method.standing}))
        """, tmp_path, demo_site)
    assert json.loads(proc.stdout) == {
        "names": ["tpra", "latp", "grop", "llm-grop", "shuffled"],
        "origin": "plugin llm-grop-demo 0.1", "name": "shuffled", "standing": "uniform"}


def test_plugin_method_is_unknown_when_not_installed(tmp_path: Path) -> None:
    out = tmp_path / "bench"
    proc = _llm_grop(["bench", "--tasks", "1", "--trials", "2", "--methods", "shuffled",
                      "--workers", "2", "--out", str(out), "--no-images", "-q"], tmp_path)
    line = _one_line_error(proc)
    assert "unknown method 'shuffled'" in line
    assert line.startswith("llm-grop: error: --methods:")
    assert not out.exists()


# --- methods registered at run time ---------------------------------------------------------


def test_method_registered_at_run_time_reaches_spawned_workers(tmp_path: Path) -> None:
    helpers = tmp_path / "helpers"
    helpers.mkdir()
    (helpers / "my_methods.py").write_text(textwrap.dedent("""\
        from llm_grop.methods.base import ComposedMethod

        MINE = ComposedMethod("mine", "random arrangement, utility standing, first plan",
                              uses_llm=False, standing="utility", best_of_all=False)
        """), encoding="utf-8")
    out = tmp_path / "bench"
    proc = _python("""\
        import json
        import sys
        from pathlib import Path

        from llm_grop.experiment.runner import Experiment, run_experiment
        from llm_grop.experiment.trial import TrialSettings
        from llm_grop.methods.registry import register_method
        from my_methods import MINE

        if __name__ == "__main__":
            register_method(MINE)
            exp = Experiment(tasks=(1,), trials=2, methods=("mine",),
                             settings=TrialSettings.of(llm="replay"))
            outcome = run_experiment(exp, Path(sys.argv[1]) / "bench", workers=2)
            print(json.dumps([[r.method, r.trial] for r in outcome.rows]))
        """, tmp_path, helpers)
    assert json.loads(proc.stdout) == [["mine", 0], ["mine", 1]]
    assert [(r.method, r.trial) for r in _rows(out)] == [("mine", 0), ("mine", 1)]


@dataclass(frozen=True)
class _Hooked(ComposedMethod):
    """A method with a callback: picklable only when the callback is."""

    hook: Callable[[], object] = print


def _local_method(name: str) -> Method:
    """A method whose class is defined in a function: pickle cannot find it by name."""

    @dataclass(frozen=True)
    class Local(ComposedMethod):
        pass

    return Local(name, "defined in a function", uses_llm=False, standing="uniform",
                 best_of_all=False)


@pytest.fixture
def forget_runtime() -> Iterator[list[str]]:
    """Names to unregister after the test, so the global method registry stays clean."""
    names: list[str] = []
    yield names
    for name in names:
        METHODS.unregister(name)


@pytest.mark.parametrize("make", [
    pytest.param(_local_method, id="local-class"),
    pytest.param(lambda name: _Hooked(name, "holds a lambda", uses_llm=False,
                                      standing="uniform", best_of_all=False,
                                      hook=lambda: None), id="lambda-attribute"),
])
def test_unpicklable_run_time_method_is_refused_for_workers(
        make: Callable[[str], Method], forget_runtime: list[str]) -> None:
    method = make("unpicklable-demo")
    forget_runtime.append(method.name)
    register_method(method)
    assert METHODS.get("unpicklable-demo") is method  # usable in this process
    with pytest.raises(BadInput, match="cannot reach worker processes") as caught:
        plugins.registered()
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith("method: method 'unpicklable-demo' was registered at run time")
    METHODS.unregister("unpicklable-demo")
    _, entries = plugins.registered().get(METHODS.group, (METHODS.module, {}))
    assert "unpicklable-demo" not in entries


def test_picklable_run_time_method_is_handed_over(forget_runtime: list[str]) -> None:
    method = _Hooked("picklable-demo", "holds a module-level function", uses_llm=False,
                     standing="uniform", best_of_all=False, hook=print)
    forget_runtime.append(method.name)
    register_method(method)
    module, entries = plugins.registered()[METHODS.group]
    assert module == "llm_grop.methods.registry"
    assert entries["picklable-demo"] == method


# --- plugins that fail --------------------------------------------------------------------


@pytest.mark.parametrize(("args", "expected"), [
    pytest.param(["--methods", "broken"],
                 ["--methods: plugin 'broken' from llm-grop-faulty 0.1 failed to load "
                  "(llm_grop_faulty_boom:METHOD): RuntimeError: demo plugin cannot start"],
                 id="import-raises"),
    pytest.param(["--methods", "absent"],
                 ["--methods: plugin 'absent' from llm-grop-faulty 0.1 failed to load",
                  "llm_grop_faulty:NO_SUCH", "AttributeError"],
                 id="missing-attribute"),
    pytest.param(["--methods", "grop", "--simulator", "broken-sim"],
                 ["--simulator: plugin 'broken-sim' from llm-grop-faulty 0.1 failed to load",
                  "ModuleNotFoundError", "llm_grop_faulty_absent"],
                 id="simulator-module-missing"),
    pytest.param(["--methods", "misnamed"],
                 ["--methods: plugin llm-grop-faulty 0.1: method registered as 'misnamed' "
                  "is named 'other'; the two must agree"],
                 id="misnamed"),
    pytest.param(["--methods", "classy"],
                 ["--methods: plugin llm-grop-faulty 0.1: 'classy' is not a method instance"],
                 id="class-not-instance"),
    pytest.param(["--methods", "grop", "--simulator", "failing-sim"],
                 ["--simulator: plugin llm-grop-faulty 0.1: simulator 'failing-sim' failed to "
                  "start: RuntimeError: no physics engine here"],
                 id="factory-raises"),
    pytest.param(["--methods", "grop", "--simulator", "function-sim"],
                 ["--simulator: plugin llm-grop-faulty 0.1: simulator 'function-sim' is not "
                  "a subclass of llm_grop.simulation.base.Simulator"],
                 id="simulator-not-declared"),
    pytest.param(["--methods", "llm-grop", "--llm", "not-an-llm"],
                 ["--llm: plugin llm-grop-faulty 0.1: backend 'not-an-llm' made an object "
                  "that does not follow the LLM protocol (it needs backend, model, "
                  "supports_schema, cache_identity, complete, close)"],
                 id="backend-makes-no-llm"),
])
def test_faulty_plugin_gives_one_line_error(args: list[str], expected: list[str],
                                            faulty_site: Path, tmp_path: Path) -> None:
    out = tmp_path / "bench"
    proc = _llm_grop(["bench", "--tasks", "1", "--trials", "1", *args, "--out", str(out),
                      "--no-images", "-q"], tmp_path, faulty_site)
    line = _one_line_error(proc)
    assert line.startswith("llm-grop: error: ")
    for fragment in expected:
        assert fragment in line
    assert not out.exists()  # reported before any trial runs


def test_faulty_plugins_do_not_break_the_others(faulty_site: Path, tmp_path: Path) -> None:
    proc = _python("""\
        import json
        from llm_grop.methods.registry import METHODS, available_methods, get_method

        print(json.dumps({"names": available_methods(), "fine": get_method("fine").name,
                          "origin": METHODS.origin("fine")}))
        """, tmp_path, faulty_site)
    assert json.loads(proc.stdout) == {
        "names": ["tpra", "latp", "grop", "llm-grop", "absent", "broken", "classy", "fine",
                  "misnamed"],
        "fine": "fine", "origin": "plugin llm-grop-faulty 0.1"}


# --- precedence -----------------------------------------------------------------------------


def test_plugin_cannot_take_a_builtin_name(tmp_path: Path) -> None:
    # Every shadowing entry points at a module that does not exist: using one would fail.
    site = _write_dist_info(tmp_path / "site", "llm-grop-shadow", """\
        [llm_grop.methods]
        GROP = llm_grop_shadow_absent:GROP

        [llm_grop.simulators]
        kinematic2d = llm_grop_shadow_absent:SIMULATOR

        [llm_grop.llm_backends]
        replay = llm_grop_shadow_absent:LLM
        """, {})
    proc = _python("""\
        import json
        import logging

        logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s %(message)s")

        from llm_grop.llm.registry import BACKENDS
        from llm_grop.llm.replay import ReplayLLM
        from llm_grop.methods.registry import GROP, METHODS
        from llm_grop.simulation.registry import SIMULATORS, create_simulator

        registries = {"method": (METHODS, "grop"), "simulator": (SIMULATORS, "kinematic2d"),
                      "backend": (BACKENDS, "replay")}
        print(json.dumps({
            "plugins": {k: sorted(r.plugins()) for k, (r, _) in registries.items()},
            "origins": {k: r.origin(name) for k, (r, name) in registries.items()},
            "names": METHODS.names(),
            "grop is built-in": METHODS.get("grop") is GROP,
            "simulator": create_simulator("kinematic2d").name,
            "backend is built-in": BACKENDS.get("replay") is ReplayLLM,
        }))
        """, tmp_path, site)
    assert json.loads(proc.stdout) == {
        "plugins": {"method": [], "simulator": [], "backend": []},
        "origins": {"method": "llm-grop", "simulator": "llm-grop", "backend": "llm-grop"},
        "names": ["tpra", "latp", "grop", "llm-grop"],
        "grop is built-in": True,
        "simulator": "kinematic2d",
        "backend is built-in": True,
    }
    for kind, name in (("method", "grop"), ("simulator", "kinematic2d"),
                       ("backend", "replay")):
        assert (f"WARNING llm_grop.plugins plugin {kind} {name!r} from llm-grop-shadow 0.1 "
                f"is ignored: llm-grop ships a {kind} of that name") in proc.stderr


def test_entry_defined_in_an_interactive_main_is_refused_before_the_bench(tmp_path: Path
                                                                         ) -> None:
    """A factory defined in ``python -c`` pickles by name but no worker can import it."""
    code = textwrap.dedent("""\
        import sys
        from pathlib import Path
        from llm_grop.errors import BadInput
        from llm_grop.experiment.runner import Experiment, run_experiment
        from llm_grop.experiment.trial import TrialSettings
        from llm_grop.simulation.kinematic2d import Kinematic2D
        from llm_grop.simulation.registry import register_simulator

        class Mine(Kinematic2D):
            name = "mine"

        register_simulator("mine", Mine)
        out = Path(sys.argv[1])
        try:
            run_experiment(Experiment((1,), 1, ("grop",), TrialSettings.of(simulator="mine")),
                           out, workers=2)
        except BadInput as exc:
            print(exc)
        print("exists" if out.exists() else "absent")
        """)
    out = tmp_path / "bench"
    proc = subprocess.run([sys.executable, "-c", code, str(out)], capture_output=True,
                          text=True, timeout=TIMEOUT_S, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "simulator: simulator 'mine' was registered at run time but cannot reach worker " \
           "processes (it was defined in an interactive __main__)" in proc.stdout
    assert proc.stdout.strip().endswith("absent")
