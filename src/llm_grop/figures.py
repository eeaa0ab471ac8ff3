"""The house style that every picture and chart llm-grop draws shares: resolution, page
colour and lettering, and the PNG writer.

Only matplotlib's object API and its Agg canvas are used (no pyplot state); the PNG
carries no version or time stamp, so the same figure always gives the same bytes. It sits
below :mod:`llm_grop.render` (a table, a room) and the experiment's charts alike, so a
chart of results draws no table and loads no renderer.
"""

from __future__ import annotations

import os
import secrets
from pathlib import Path
from typing import TYPE_CHECKING

from llm_grop.errors import BadInput

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: Resolution of every picture, dots per inch.
DPI = 150
#: Colour of the page.
BACKGROUND = "#ffffff"
# Fixed style, so that a user's matplotlibrc cannot change the picture.
STYLE = {"font.family": "DejaVu Sans", "font.size": 9.0, "axes.linewidth": 0.8,
         "text.color": "#111111", "axes.edgecolor": "#666666", "xtick.color": "#444444",
         "ytick.color": "#444444", "axes.labelcolor": "#222222"}


def save_png(fig: Figure, path: Path, *, dpi: int = DPI) -> None:
    """Write ``fig`` to ``path`` as PNG at ``dpi`` dots per inch, replacing it atomically.

    The PNG carries no software or time stamp, so the same figure gives the same bytes.
    Raises :class:`BadInput` (one line, naming ``path``) if it cannot be written.
    """
    tmp = path.with_name(f".{path.name}.{os.getpid()}-{secrets.token_hex(4)}.tmp")
    try:
        fig.savefig(tmp, format="png", dpi=dpi, facecolor=BACKGROUND,
                    metadata={"Software": None})
        tmp.replace(path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise BadInput(f"image {path}: cannot write ({exc.strerror or exc})") from None
