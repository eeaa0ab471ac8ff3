"""Run by ``llm-grop doctor`` as a script in a process of its own, because loading an
OpenGL library is process-global: renders one frame of a tiny MuJoCo model offscreen and
prints one JSON object: ``given`` (``MUJOCO_GL`` as set, or ``None``), ``mujoco_gl`` (the
backend in use), ``size`` (width, height in pixels) and ``lit`` (the fraction of pixels
not black), or ``error``."""

from __future__ import annotations

import json
import os
from typing import Any

#: A lit red box in front of MuJoCo's default free camera.
_MODEL = """<mujoco><worldbody><light pos="0 0 2"/>
<geom type="box" size=".1 .1 .1" rgba="1 0 0 1"/></worldbody></mujoco>"""

#: Width and height of the frame, in pixels.
_SIZE = 32


def main() -> None:
    """Render the frame and print what happened."""
    given = os.environ.get("MUJOCO_GL")
    result: dict[str, Any] = {"given": given, "mujoco_gl": given}
    try:
        # The package picks MUJOCO_GL when it is unset, as every command does.
        import llm_grop.simulation.mujoco  # noqa: F401

        result["mujoco_gl"] = os.environ.get("MUJOCO_GL")
        import mujoco

        model = mujoco.MjModel.from_xml_string(_MODEL)
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        renderer = mujoco.Renderer(model, height=_SIZE, width=_SIZE)
        try:
            renderer.update_scene(data)
            frame = renderer.render()
        finally:
            renderer.close()
        result["size"] = [int(frame.shape[1]), int(frame.shape[0])]
        result["lit"] = float((frame.max(axis=2) > 0).mean())
    except Exception as exc:  # noqa: BLE001 - every failure is the finding to report
        result["error"] = f"{type(exc).__name__}: {' '.join(str(exc).split())}"
    print(json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
