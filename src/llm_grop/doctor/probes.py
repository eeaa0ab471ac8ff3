"""The checks that need a process of their own: llama.cpp's build and MuJoCo's offscreen
OpenGL. A native llama.cpp can die of an illegal instruction, and OpenGL libraries are
loaded once per process, so each is tried in a child Python with a time limit."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

from llm_grop.doctor.check import Check, Status, one_line, pip_command
from llm_grop.simulation.mujoco.options import GL_APT

#: Longest a probe may take, in seconds (a first OSMesa frame takes about one).
PROBE_TIMEOUT_S = 60.0

#: llama.cpp's names of instruction set extensions that a portable build leaves out: the
#: default native build turns them on where the CPU has them, and crashes on CPUs with AMX.
_NATIVE_ONLY = re.compile(r"^(AVX512|AMX)")

#: llama.cpp's feature names whose /proc/cpuinfo flag is not the name in lower case.
_CPUINFO_FLAG = {"SSE3": "pni", "AVX512": "avx512f", "AVX512_VBMI": "avx512vbmi"}

#: llama.cpp's features that are instruction set extensions (the others, such as
#: LLAMAFILE or OPENMP, are code paths any CPU runs).
_ISA = {"SSE3", "SSSE3", "AVX", "AVX_VNNI", "AVX2", "F16C", "FMA", "BMI2", "AVX512",
        "AVX512_VBMI", "AVX512_VNNI", "AVX512_BF16", "AMX_INT8"}

#: The apt packages behind each offscreen backend of MuJoCo.

_REBUILD = "scripts/setup.sh"
_GL_FIX = "sudo apt-get install libosmesa6 && export MUJOCO_GL=osmesa"


def run_probe(script: str, timeout_s: float = PROBE_TIMEOUT_S) -> dict[str, Any]:
    """The JSON object a probe script beside this module prints, run by this interpreter
    in a fresh process; ``{"error": ...}`` when it crashed, hung or printed none."""
    path = Path(__file__).with_name(script)
    try:
        # -P: the script's folder is not put on sys.path, where its neighbours would
        # shadow modules of the same name.
        done = subprocess.run([sys.executable, "-P", str(path)], capture_output=True,
                              text=True, errors="replace", timeout=timeout_s,
                              stdin=subprocess.DEVNULL, env=dict(os.environ), check=False)
    except subprocess.TimeoutExpired:
        return {"error": f"no answer within {timeout_s:g} s"}
    except OSError as exc:
        return {"error": f"could not start a Python process ({exc.strerror or exc})"}
    if done.returncode < 0:
        try:
            name = signal.Signals(-done.returncode).name
        except ValueError:
            name = f"signal {-done.returncode}"
        return {"error": f"the process died of {name}"}
    for line in reversed(done.stdout.splitlines()):
        if line.startswith("{"):
            try:
                found = json.loads(line)
            except json.JSONDecodeError:
                break
            if isinstance(found, dict):
                return found
    last = [line for line in done.stderr.splitlines() if line.strip()]
    return {"error": one_line(last[-1]) if last else f"exit status {done.returncode}"}


def build_features(system_info: str) -> list[str]:
    """The CPU features llama.cpp's system info says it was compiled for, in its order."""
    return re.findall(r"(\w+) = 1\b", system_info)


def llama_build_check(version: str | None, system_info: str | None, error: str | None,
                      cpu: frozenset[str] | None) -> Check:
    """The llama.cpp check from what the probe found: the build must leave out AVX-512
    and AMX, and use no instruction ``cpu`` (its /proc/cpuinfo flags, if known) lacks."""
    name = "llama.cpp"
    if error is not None or system_info is None:
        if error and "No module named 'llama_cpp'" in error:
            return Check(name, Status.FAIL, "llama-cpp-python is not installed (the "
                         "embedded LLM runs on it); scripts/setup.sh builds it portably",
                         _REBUILD)
        return Check(name, Status.FAIL, f"llama-cpp-python is unusable: {error}",
                     f"{pip_command()} uninstall -y llama-cpp-python && {_REBUILD}")
    isa = [f for f in build_features(system_info) if f in _ISA]
    native = [f for f in isa if _NATIVE_ONLY.match(f)]
    rebuild = f"{pip_command()} uninstall -y llama-cpp-python && {_REBUILD}"
    if native:
        return Check(name, Status.FAIL, f"llama-cpp-python {version} is a native build "
                     f"({', '.join(native)}), which crashes on CPUs with AVX-512/AMX; "
                     "a portable build is needed", rebuild)
    lacking = [f for f in isa
               if cpu is not None and _CPUINFO_FLAG.get(f, f.lower()) not in cpu]
    if lacking:
        return Check(name, Status.FAIL, f"llama-cpp-python {version} uses "
                     f"{', '.join(lacking)}, which this CPU lacks", rebuild)
    return Check(name, Status.OK, f"llama-cpp-python {version}, portable build "
                 f"({' '.join(isa) or 'no SIMD'}; no AVX-512, no AMX)")


def cpu_flags() -> frozenset[str] | None:
    """This CPU's instruction set flags from /proc/cpuinfo; ``None`` where it has none
    (not Linux, or not x86)."""
    try:
        text = Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    for line in text.splitlines():
        key, _, value = line.partition(":")
        if key.strip() == "flags":
            return frozenset(value.split())
    return None


def check_llama_build() -> Check:
    """Whether the installed llama-cpp-python is a portable build (loads no model)."""
    found = run_probe("llama_probe.py")
    return llama_build_check(found.get("version"), found.get("system_info"),
                             found.get("error"), cpu_flags())


def check_mujoco_gl() -> Check:
    """Whether MuJoCo renders one frame offscreen, in a fresh process as a command would."""
    found = run_probe("gl_probe.py")
    # A probe that died said nothing: the value it was given is this process's.
    given = found.get("given", os.environ.get("MUJOCO_GL"))
    backend = found.get("mujoco_gl", given)
    if given:
        shown = f"MUJOCO_GL={given}"
    else:
        shown = f"MUJOCO_GL unset (llm-grop picks {backend})" if backend \
            else "MUJOCO_GL unset (no libOSMesa or libEGL found)"
    error = found.get("error")
    if error is None and found.get("lit", 0.0) <= 0.0:
        error = "the frame came out black"
    if error is not None:
        pyopengl = os.environ.get("PYOPENGL_PLATFORM")
        if error.startswith("ModuleNotFoundError"):
            fix = f"{pip_command()} install -e ."
        elif backend and pyopengl and pyopengl.lower() != backend.lower():
            fix = "unset PYOPENGL_PLATFORM"
        elif backend in GL_APT:
            fix = f"sudo apt-get install {GL_APT[backend]}"
            fix += "" if backend == "osmesa" else f" (or: {_GL_FIX})"
        else:
            fix = _GL_FIX
        return Check("mujoco gl", Status.FAIL, f"{shown}: MuJoCo cannot render offscreen "
                     f"({error})", fix)
    width, height = found.get("size", [0, 0])
    return Check("mujoco gl", Status.OK, f"{shown}: rendered a {width}x{height} frame "
                 "offscreen")
