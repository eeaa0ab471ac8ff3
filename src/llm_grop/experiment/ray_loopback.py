"""The node address of the Ray executor's driver: 127.0.0.1 for a cluster it starts, the
cluster's own host for one it joins at a loopback address (127.0.0.0/8 or ``localhost``),
Ray's own choice otherwise.

On Linux Ray takes this machine's network address for a node's, and rewrites ``127.0.0.1``
and ``localhost`` into it wherever it is handed one: in the address it joins (so a cluster
whose nodes run on 127.0.0.1 is dialled at the network address, where nothing answers) and
in ``_node_ip_address``. Its switch for macOS and Windows,
``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0``, makes it keep loopback addresses as they are and
take 127.0.0.1 for a node it starts. Ray reads the switch once, when it is first imported,
and the processes of a cluster this one starts inherit it; this module never imports Ray.
"""

from __future__ import annotations

import ipaddress
import os
import sys

#: The node address of a Ray cluster the executor starts.
LOOPBACK = "127.0.0.1"
#: Ray's switch that keeps loopback node addresses ("0"), read when Ray is imported.
RAY_LOOPBACK_SWITCH = "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"


def node_address(address: str | None) -> str | None:
    """The node address a driver takes for the Ray cluster at ``address``.

    :data:`LOOPBACK` for a cluster it starts (``address`` ``None`` or ``local``); the host
    of ``host:port`` when that host is a loopback one (``localhost`` is 127.0.0.1); ``None``,
    Ray's own choice, for any other address (another host, ``auto``, a Ray Client
    ``ray://`` address, whose driver runs no node here).
    """
    if address is None or address == "local":
        return LOOPBACK
    host, sep, port = address.rpartition(":")
    if "://" in address or not sep or not port.isdigit():
        return None
    if host == "localhost":
        return LOOPBACK
    try:
        ip = ipaddress.ip_address(host)
    except ValueError:
        return None
    # IPv4 only: Ray's loopback node address is 127.0.0.1, never ::1.
    return str(ip) if ip.version == 4 and ip.is_loopback else None


def use_loopback() -> None:
    """Have Ray keep loopback node addresses, in this process and in those it starts."""
    os.environ[RAY_LOOPBACK_SWITCH] = "0"
    constants = sys.modules.get("ray._private.ray_constants")
    if constants is not None:
        # Ray was imported before and has read the switch already; its functions look the
        # setting up on this module each time they run.
        constants.ENABLE_RAY_CLUSTER = False
