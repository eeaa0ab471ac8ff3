"""``llm-grop doctor``'s checks: is every part llm-grop needs there, and which optional
parts are missing, each with the command that fixes it. Nothing here uses the network,
except a request to the OpenAI-compatible server the user configured.

Each check returns a :class:`Check`. A ``fail`` is a needed part missing: the Python
version, a portable llama.cpp build, offscreen OpenGL for MuJoCo, the embedded model's
file, and a configured server that answers and lists the model. Chromium and the optional
extras (ratings, ray, serve, viz, ros) only warn.
"""

from __future__ import annotations

from collections.abc import Callable

from llm_grop.doctor.check import MARKS, Check, Status, report_line
from llm_grop.doctor.installed import (
    EXTRAS,
    check_chromium,
    check_extra,
    check_model_file,
    check_python,
    extra_requirements,
)
from llm_grop.doctor.probes import check_llama_build, check_mujoco_gl
from llm_grop.doctor.server import check_auto, check_server

__all__ = ["MARKS", "Check", "Status", "report_line", "run_checks", "checks", "healthy"]


def checks(base_url: str | None = None, model: str | None = None,
           api_key: str | None = None) -> list[Callable[[], Check]]:
    """Every check, in the order of the report, not yet run; ``base_url``, ``model`` and
    ``api_key`` configure the OpenAI-compatible server's (``base_url=None``: skipped)."""
    from llm_grop.llm.embedded import BUNDLED_FILE, BUNDLED_PACKAGE

    return [
        check_python,
        check_llama_build,
        lambda: check_model_file(BUNDLED_PACKAGE, BUNDLED_FILE),
        check_mujoco_gl,
        check_chromium,
        *[(lambda extra=extra: check_extra(extra, extra_requirements(extra)))
          for extra in EXTRAS],
        lambda: check_server(base_url, model, api_key),
        lambda: check_auto(base_url, model),
    ]


def run_checks(base_url: str | None = None, model: str | None = None,
               api_key: str | None = None) -> list[Check]:
    """Run every check (see :func:`checks`) and return what each found."""
    return [check() for check in checks(base_url, model, api_key)]


def healthy(found: list[Check]) -> bool:
    """Whether every needed part is there: no check failed (warnings are optional parts)."""
    return all(check.status is not Status.FAIL for check in found)
