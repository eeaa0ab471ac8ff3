"""Ray clusters the tests start (``ray.init``, ``ray.cluster_utils.Cluster``, a bench's own)
run on loopback only, never on this machine's network address: Ray's loopback switch is set
before Ray is imported (and inherited by every process a test starts), so that 127.0.0.1
stays 127.0.0.1 in every address Ray is handed, and the clusters the tests start name
127.0.0.1 as their nodes' address too."""

from __future__ import annotations

from llm_grop.experiment.ray_loopback import use_loopback

use_loopback()
