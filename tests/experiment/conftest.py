"""Ray clusters the tests start (``ray.init``, ``ray.cluster_utils.Cluster``, a bench's own)
listen on loopback only, never on this machine's network address: Ray then takes the node's
address as it does on macOS and Windows, 127.0.0.1. Set before Ray is imported, and
inherited by every process a test starts."""

from __future__ import annotations

import os

os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
