"""The website's pages and the report page: Jinja templates and the rating guidelines,
both in files beside this module."""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Any

import jinja2
import yaml

HERE = Path(__file__).resolve().parent
TEMPLATES = HERE / "templates"
STATIC = HERE / "static"


@cache
def environment() -> jinja2.Environment:
    """The templates, HTML-escaped."""
    return jinja2.Environment(loader=jinja2.FileSystemLoader(TEMPLATES),
                              autoescape=jinja2.select_autoescape(["html"]),
                              undefined=jinja2.StrictUndefined)


@cache
def guidelines() -> dict[str, Any]:
    """Table III of the paper: ``intro`` and ``points`` (1-5 -> guideline)."""
    data = yaml.safe_load((HERE / "guidelines.yaml").read_text(encoding="utf-8"))
    return {"intro": data["intro"], "points": {int(k): v for k, v in data["points"].items()}}


def render(name: str, **context: Any) -> str:
    """The page ``name`` (a template file) with ``context``; unset page fields are empty."""
    base = {"csrf": None, "rater": None, "error": None, "guidelines": guidelines()}
    return environment().get_template(name).render(**(base | context))
