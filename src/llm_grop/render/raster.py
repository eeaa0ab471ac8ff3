"""Writing images that simulators render (RGB arrays) to files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image


def save_rgb_png(image: np.ndarray, path: str | Path) -> Path:
    """Write an RGB image (height x width x 3, uint8) to ``path`` as PNG; the path."""
    out = Path(path)
    Image.fromarray(np.asarray(image, dtype=np.uint8)).save(out, format="PNG")
    return out
