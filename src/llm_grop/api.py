"""The public Python API: the same operations the command line offers."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from os import PathLike
from pathlib import Path

from llm_grop.arrangement.pipeline import ArrangementResult, ArrangeOptions, arrange_items
from llm_grop.errors import BadInput
from llm_grop.llm.base import LLM, BackendOptions, CallLog, create_llm
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import items_from_names, parse_request
from llm_grop.world.table import Table
from llm_grop.world.tasks import get_task, load_tasks


def make_llm(llm: str | LLM = "embedded", options: BackendOptions | None = None,
             record: str | PathLike[str] | None = None) -> CallLog:
    """A logged LLM: a backend by name (or an :class:`LLM` instance), recording to ``record``."""
    backend = create_llm(llm, options) if isinstance(llm, str) else llm
    return CallLog(backend, Path(record) if record is not None else None)


def arrange(request: str | None = None, *, task: int | None = None,
            llm: str | LLM | CallLog = "embedded", llm_options: BackendOptions | None = None,
            table: Table | None = None, seed: int = 0, catalog: Catalog | None = None,
            catalog_files: Sequence[str | PathLike[str]] = (),
            options: ArrangeOptions | None = None, record: str | PathLike[str] | None = None,
            on_event: Callable[[str], None] | None = None) -> ArrangementResult:
    """Arrange the objects of ``request`` (or of the paper's Table I ``task``) on ``table``.

    ``llm`` is a backend name (``"embedded"``, ``"openai"``, ``"replay"``), an
    :class:`LLM`, or a :class:`CallLog`. ``seed`` fixes every LLM call's seed and
    the sampler, so the same inputs give the same result. ``record`` appends each
    LLM call to a JSONL file that ``llm="replay"`` can read back.
    """
    catalog = catalog or Catalog.load(catalog_files)
    if task is not None:
        t = get_task(task, load_tasks())
        items = items_from_names(t.objects, catalog)
        text = request or t.request
    elif request is not None:
        parsed = parse_request(request, catalog)
        items, text = parsed.items, parsed.text
    else:
        raise BadInput("request: give a request or a task number")
    log = llm if isinstance(llm, CallLog) else make_llm(llm, llm_options, record)
    return arrange_items(text, items, log, catalog, table or Table(), seed, options, on_event)
