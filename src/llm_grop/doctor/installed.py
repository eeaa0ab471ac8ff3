"""The checks of what is installed: the Python version, the embedded model's file,
Chromium for the browser tests and the optional extras, read from package metadata and
the file system without importing the packages."""

from __future__ import annotations

import os
import platform
import shlex
import subprocess
from collections.abc import Sequence
from importlib import metadata, resources
from pathlib import Path

from packaging.requirements import InvalidRequirement, Requirement
from packaging.specifiers import SpecifierSet

from llm_grop.doctor.check import Check, Status, one_line, pip_command, python_shown, shown_path

#: The distribution whose metadata says what llm-grop needs.
DISTRIBUTION = "llm-grop"

#: The optional extras the doctor checks (``dev`` is the test tools, not a feature).
EXTRAS = ("ratings", "ray", "serve", "viz", "ros")

#: Debian's Chromium, which the rating website's browser tests drive through Playwright.
CHROMIUM = Path("/usr/bin/chromium")

#: The first bytes of every GGUF file.
_GGUF_MAGIC = b"GGUF"

_INSTALL_SELF = "pip install -e ."


def check_python() -> Check:
    """Whether this Python is one llm-grop's metadata (``requires-python``) accepts."""
    version = platform.python_version()
    try:
        needed = metadata.metadata(DISTRIBUTION).get("Requires-Python") or ""
    except metadata.PackageNotFoundError:
        return Check("python", Status.FAIL, f"{version}, but llm-grop is not installed "
                     "here (no package metadata)", f"{python_shown()} -m {_INSTALL_SELF}")
    if needed and not SpecifierSet(needed).contains(version, prereleases=True):
        return Check("python", Status.FAIL, f"{version} at {python_shown()}, llm-grop "
                     f"needs {needed}",
                     f"rm -rf .venv && PYTHON=<a python3 {needed}> scripts/setup.sh")
    return Check("python", Status.OK, f"{version} at {python_shown()} (llm-grop needs "
                 f"{needed or 'any'})")


def check_model_file(package: str, file: str) -> Check:
    """Whether the GGUF ``file`` inside ``package`` exists, is readable and is GGUF."""
    distribution = package.replace("_", "-")
    fix = f"{pip_command()} install --force-reinstall {distribution}"
    try:
        resource = resources.files(package).joinpath(file)
    except ModuleNotFoundError:
        return Check("embedded model", Status.FAIL, f"the {distribution} package, which "
                     f"holds {file}, is not installed", fix)
    try:
        with resources.as_file(resource) as path, open(path, "rb") as handle:
            magic = handle.read(len(_GGUF_MAGIC))
            size_mb = os.fstat(handle.fileno()).st_size / 1e6
            where = shown_path(Path(path))
    except OSError as exc:
        return Check("embedded model", Status.FAIL, f"{file} in {distribution}: "
                     f"{exc.strerror or exc}", fix)
    if magic != _GGUF_MAGIC:
        return Check("embedded model", Status.FAIL, f"{where} is not a GGUF file", fix)
    return Check("embedded model", Status.OK, f"{size_mb:.1f} MB, readable: {where} "
                 f"({distribution} {_version(distribution)})")


def check_chromium(executable: Path = CHROMIUM) -> Check:
    """Whether Chromium and the playwright package are there for the browser tests
    (optional: only the tests need them)."""
    missing, fixes = [], []
    if not os.access(executable, os.X_OK):
        missing.append(f"no Chromium at {executable}")
        fixes.append("sudo apt-get install chromium")
    playwright = _version("playwright")
    if playwright is None:
        missing.append("the playwright package is not installed")
        fixes.append(f"{pip_command()} install playwright")
    if missing:
        return Check("chromium", Status.WARN, "; ".join(missing) + " (only the browser "
                     "tests need them)", " && ".join(fixes))
    return Check("chromium", Status.OK, f"{_chromium_version(executable)} at {executable}; "
                 f"playwright {playwright}")


def extra_requirements(extra: str) -> list[Requirement]:
    """The packages llm-grop's ``extra`` adds on this platform, from its metadata."""
    try:
        texts = metadata.requires(DISTRIBUTION) or []
    except metadata.PackageNotFoundError:
        return []
    out = []
    for text in texts:
        try:
            requirement = Requirement(text)
        except InvalidRequirement:
            continue
        marker = requirement.marker
        # A base dependency's marker (sys_platform alone) holds for every extra too.
        if marker is None or "extra" not in str(marker) \
                or not marker.evaluate({"extra": extra}):
            continue
        requirement.marker = None
        out.append(requirement)
    return out


def check_extra(extra: str, requirements: Sequence[Requirement]) -> Check:
    """Whether every package of the optional ``extra`` is installed in a version it
    accepts (optional: a missing one is a warning)."""
    name = f"extra {extra}"
    if not requirements:
        return Check(name, Status.WARN, f"llm-grop's metadata lists no [{extra}] extra",
                     f"{python_shown()} -m {_INSTALL_SELF}")
    problems, wanted = [], []
    for requirement in requirements:
        version = _version(requirement.name)
        if version is None:
            problems.append(f"{requirement.name} missing")
        elif not requirement.specifier.contains(version, prereleases=True):
            problems.append(f"{requirement.name} {version} (needs {requirement.specifier})")
        else:
            continue
        wanted.append(shlex.quote(f"{requirement.name}{requirement.specifier}"))
    if problems:
        return Check(name, Status.WARN, f"[{extra}] incomplete: {', '.join(problems)}",
                     f"{pip_command()} install {' '.join(wanted)}")
    listed = ", ".join(f"{r.name} {_version(r.name)}" for r in requirements)
    return Check(name, Status.OK, f"[{extra}] installed: {listed}")


def _version(distribution: str) -> str | None:
    """An installed distribution's version, or ``None``."""
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return None


def _chromium_version(executable: Path) -> str:
    """``Chromium 1xx.…`` as the browser prints it, or ``Chromium`` if it will not say."""
    try:
        done = subprocess.run([str(executable), "--version"], capture_output=True, text=True,
                              timeout=30, stdin=subprocess.DEVNULL, check=False)
    except (OSError, subprocess.TimeoutExpired):
        return "Chromium"
    first = one_line(done.stdout.splitlines()[0]) if done.stdout.strip() else ""
    return first.split(" built on ")[0] or "Chromium"
