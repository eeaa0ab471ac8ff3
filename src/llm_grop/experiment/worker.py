"""What a worker does with one trial, whichever executor runs it.

A :class:`Job` is one trial of one experiment (a bench has one, a sweep one per cell). A
worker process keeps a :class:`Runners`: one :class:`~llm_grop.experiment.trial.TrialRunner`
(LLM, catalog, scene and simulator, loaded once) per experiment settings it has seen, the
few most recent kept. It answers with a :class:`Done`: the trial's row, and, when the
worker may not share a file system with the driver, the pictures the trial drew, as bytes
for the driver to write (:func:`run_job` with ``ship_pictures``).
"""

from __future__ import annotations

import tempfile
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path

from llm_grop.contract.models import TrialRow
from llm_grop.experiment.trial import TrialRunner, TrialSettings, TrialSpec

#: Runners a worker keeps (a sweep's jobs come cell by cell, so a worker rarely needs an
#: older one again).
KEPT_RUNNERS = 4


@dataclass(frozen=True)
class Job:
    """Trial ``spec`` of the experiment with ``settings``; ``cell`` says which of the
    driver's experiments it belongs to (an index)."""

    cell: int
    settings: TrialSettings
    spec: TrialSpec


@dataclass(frozen=True)
class Done:
    """A finished :class:`Job`: its ``cell``, its ``row``, and ``pictures``, each
    ``(path relative to the results directory, bytes)``, when the worker shipped its
    pictures and recording rather than writing them."""

    cell: int
    row: TrialRow
    pictures: tuple[tuple[str, bytes], ...] = ()


class Runners:
    """A process's trial runners by settings, the :data:`KEPT_RUNNERS` most recent kept."""

    def __init__(self) -> None:
        self._runners: OrderedDict[TrialSettings, TrialRunner] = OrderedDict()

    def __call__(self, settings: TrialSettings) -> TrialRunner:
        """The runner for ``settings``, made on first use."""
        runner = self._runners.pop(settings, None) or TrialRunner(settings)
        self._runners[settings] = runner
        while len(self._runners) > KEPT_RUNNERS:
            self._runners.popitem(last=False)
        return runner


def run_job(job: Job, runners: Runners, *, ship_pictures: bool = False) -> Done:
    """Run ``job`` with a runner from ``runners``.

    With ``ship_pictures`` the trial draws into a temporary directory instead of the
    results directory, and its pictures come back in the :class:`Done`.
    """
    runner, s = runners(job.settings), job.settings
    if not ship_pictures or s.images is None and s.recordings is None:
        return Done(job.cell, runner(job.spec))
    with tempfile.TemporaryDirectory(prefix="llm-grop-pictures-") as scratch:
        row = runner(job.spec, images=Path(scratch) if s.images is not None else None,
                     recordings=Path(scratch) if s.recordings is not None else None)
        pictures = tuple((rel, (Path(scratch) / Path(rel).name).read_bytes())
                         for rel in (row.image, row.render, row.recording)
                         if rel is not None and (Path(scratch) / Path(rel).name).exists())
    return Done(job.cell, row, pictures)
