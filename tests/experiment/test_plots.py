"""The paper's result figures (Fig. 3 and Fig. 5) as deterministic PNG pictures."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.image import imread

from llm_grop.errors import BadInput
from llm_grop.experiment.plots import (
    AUTOMATIC,
    BARS_FIGSIZE_IN,
    HUMAN,
    METHOD_STYLES,
    SCATTER_FIGSIZE_IN,
    display_name,
    method_styles,
    plot_rating_per_task,
    plot_rating_vs_time,
)
from llm_grop.experiment.summary import Summary, summarize
from llm_grop.render.table import DPI
from rows import trial_row

PLOTS = (plot_rating_vs_time, plot_rating_per_task)


def row(method: str, task: int, rating: int, execution: float | None,
        trial: int = 0) -> dict[str, Any]:
    return trial_row(method, task, rating, execution, trial=trial)


def full_summary() -> Summary:
    rows = []
    for k, method in enumerate(("tpra", "latp", "grop", "llm-grop")):
        for task in range(1, 9):
            for trial in range(3):
                rating = 1 + (k + task + trial) % 5
                rows.append(row(method, task, rating, 60.0 + 10 * k + task + trial, trial))
    return summarize(rows)


def no_execution_summary() -> Summary:
    """``tpra`` never executed a plan; ``grop`` has a single trial (no SE)."""
    return summarize([row("tpra", 1, 1, None), row("tpra", 2, 1, None, 1),
                      row("llm-grop", 1, 5, 50.0), row("llm-grop", 1, 4, 55.0, 1),
                      row("llm-grop", 2, 4, 52.0), row("grop", 2, 2, 48.0)])


def pixels(path: Path) -> np.ndarray:
    return imread(path)[:, :, :3] * 255.0


def count_color(image: np.ndarray, hex_color: str, tol: float = 4.0) -> int:
    target = np.array([int(hex_color[i:i + 2], 16) for i in (1, 3, 5)], dtype=float)
    return int(np.all(np.abs(image - target) < tol, axis=2).sum())


@pytest.mark.parametrize(("plot", "size"), [(plot_rating_vs_time, SCATTER_FIGSIZE_IN),
                                            (plot_rating_per_task, BARS_FIGSIZE_IN)])
def test_png_written_with_fixed_size(tmp_path: Path, plot: Any,
                                     size: tuple[float, float]) -> None:
    path = tmp_path / "fig.png"
    plot(full_summary(), path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    image = imread(path)
    assert image.shape[:2] == (round(size[1] * DPI), round(size[0] * DPI))
    assert not (tmp_path / ".fig.png.tmp").exists()


@pytest.mark.parametrize("plot", PLOTS)
def test_same_input_same_bytes(tmp_path: Path, plot: Any) -> None:
    plot(full_summary(), tmp_path / "a.png")
    plot(full_summary(), str(tmp_path / "b.png"))
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()


@pytest.mark.parametrize("plot", PLOTS)
def test_different_input_different_picture(tmp_path: Path, plot: Any) -> None:
    plot(full_summary(), tmp_path / "a.png")
    plot(no_execution_summary(), tmp_path / "b.png")
    assert (tmp_path / "a.png").read_bytes() != (tmp_path / "b.png").read_bytes()


def test_every_method_colour_is_drawn(tmp_path: Path) -> None:
    plot_rating_vs_time(full_summary(), tmp_path / "scatter.png")
    plot_rating_per_task(full_summary(), tmp_path / "bars.png")
    scatter, bars = pixels(tmp_path / "scatter.png"), pixels(tmp_path / "bars.png")
    for color, _marker in METHOD_STYLES.values():
        assert count_color(scatter, color) > 20
        assert count_color(bars, color) > 2000  # eight solid bars


def test_method_without_executed_trials(tmp_path: Path) -> None:
    summary = no_execution_summary()
    plot_rating_vs_time(summary, tmp_path / "scatter.png")
    plot_rating_per_task(summary, tmp_path / "bars.png")
    tpra = METHOD_STYLES["tpra"][0]
    # No execution time: no point in Fig. 3, but its ratings still make bars in Fig. 5.
    assert count_color(pixels(tmp_path / "scatter.png"), tpra) == 0
    assert count_color(pixels(tmp_path / "scatter.png"), METHOD_STYLES["llm-grop"][0]) > 20
    assert count_color(pixels(tmp_path / "bars.png"), tpra) > 200


def test_missing_bars_are_skipped(tmp_path: Path) -> None:
    # llm-grop has no task-2 trial and grop no task-1 trial: no bar, no crash.
    summary = summarize([row("grop", 2, 3, 10.0), row("llm-grop", 1, 5, 9.0)])
    plot_rating_per_task(summary, tmp_path / "bars.png")
    image = pixels(tmp_path / "bars.png")
    assert count_color(image, METHOD_STYLES["grop"][0]) > 200
    assert count_color(image, METHOD_STYLES["llm-grop"][0]) > 200


@pytest.mark.parametrize("plot", PLOTS)
def test_empty_summary(tmp_path: Path, plot: Any) -> None:
    plot(summarize([]), tmp_path / "empty.png")
    assert imread(tmp_path / "empty.png").ndim == 3


def test_other_methods_get_distinct_styles(tmp_path: Path) -> None:
    styles = method_styles(("llm-grop", "mine", "yours"))
    assert styles["llm-grop"] == METHOD_STYLES["llm-grop"]
    assert len(set(styles.values())) == 3
    assert display_name("llm-grop") == "LLM-GROP" and display_name("mine") == "mine"
    summary = summarize([row("mine", 1, 3, 5.0), row("yours", 1, 4, 6.0)])
    for plot in PLOTS:
        plot(summary, tmp_path / "x.png")
        assert count_color(pixels(tmp_path / "x.png"), styles["mine"][0]) > 20


@pytest.mark.parametrize("plot", PLOTS)
def test_bad_paths(tmp_path: Path, plot: Any) -> None:
    with pytest.raises(BadInput, match="only PNG"):
        plot(full_summary(), tmp_path / "fig.svg")
    with pytest.raises(BadInput, match="cannot write"):
        plot(full_summary(), tmp_path / "missing" / "fig.png")


@pytest.mark.parametrize("plot", PLOTS)
def test_the_rating_axis_names_who_rated(plot, tmp_path: Path) -> None:
    """A bench's figure says its ratings are the automatic rater's; a study's report says
    people gave them: the two pictures differ, and each is the same bytes every time."""
    auto, human = tmp_path / "auto.png", tmp_path / "human.png"
    plot(full_summary(), auto)
    plot(full_summary(), human, rated_by=HUMAN)
    again = tmp_path / "again.png"
    plot(full_summary(), again, rated_by=AUTOMATIC)
    assert auto.read_bytes() == again.read_bytes() != human.read_bytes()


def test_the_labels_name_the_rater() -> None:
    from matplotlib.figure import Figure

    from llm_grop.experiment.plots import _draw_bars, _draw_scatter

    for draw in (_draw_scatter, _draw_bars):
        ax = Figure().add_subplot()
        draw(ax, full_summary(), AUTOMATIC)
        assert ax.get_ylabel().startswith("automatic rating (1-5)")
