"""The MuJoCo simulator: the dining room in 3D physics with a mobile manipulator.

Importing this package picks an offscreen OpenGL backend for MuJoCo's renderer when
``MUJOCO_GL`` is unset (OSMesa if ``libOSMesa`` is installed, else EGL if ``libEGL`` is),
because MuJoCo reads the variable once, when it is first imported, and a machine without a
screen has no other way to render. Set ``MUJOCO_GL`` yourself to choose.
"""

from __future__ import annotations

import ctypes.util
import os
import sys

if "MUJOCO_GL" not in os.environ and sys.platform.startswith("linux") \
        and "mujoco" not in sys.modules:
    for _backend, _lib in (("osmesa", "OSMesa"), ("egl", "EGL")):
        if ctypes.util.find_library(_lib):
            os.environ["MUJOCO_GL"] = _backend
            break
