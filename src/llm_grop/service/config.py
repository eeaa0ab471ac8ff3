"""What an ``llm-grop serve`` is configured with: its database, its LLM backends, its
workers, its token and its limits. Everything here is set on the server; a client only
chooses among the backends by name."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from llm_grop.errors import BadInput
from llm_grop.llm.base import BackendOptions
from llm_grop.world.request import MAX_OBJECTS

#: The shortest bearer token accepted, characters.
MIN_TOKEN_CHARS = 16


@dataclass(frozen=True)
class Limits:
    """What one client may ask of the server.

    ``body_bytes``: the largest request body (bytes actually read, chunked or not);
    ``body_depth``: how deep a JSON body's arrays and objects may nest (the body itself is
    level 1; far beyond any scene or arrangement, far below where pydantic breaks);
    ``request_chars``: the longest request text; ``objects``: most objects one request may
    set; ``run_time_s``: seconds a job may run before it is failed; ``queue``: most jobs
    waiting at once (more get 429); ``jobs_per_client``: most runs one client address may
    have waiting or running, ``requests_per_client`` most arrangements (and as many plans);
    ``wait_s``: seconds an arrangement or plan request waits for its job before the answer
    (202) says where to poll instead.
    """

    body_bytes: int = 256 * 1024
    body_depth: int = 64
    request_chars: int = 500
    objects: int = MAX_OBJECTS
    run_time_s: float = 600.0
    queue: int = 64
    jobs_per_client: int = 4
    requests_per_client: int = 32
    wait_s: float = 120.0


@dataclass(frozen=True)
class Backend:
    """One LLM backend the server offers: its registry key and how it is built."""

    name: str
    options: BackendOptions


@dataclass(frozen=True)
class ServiceConfig:
    """A server: its job database, the backends clients choose from (the first is the
    default), how many worker processes run jobs, the bearer token every request must
    carry (``None``: none, loopback only) and the limits."""

    db: Path
    backends: tuple[Backend, ...]
    workers: int = 2
    token: str | None = None
    limits: Limits = field(default_factory=Limits)
    #: The embedded model's CPU threads in each worker (``None``: the cores over workers).
    llm_threads: int | None = None
    #: Seconds an ended job (its result, files and video) is kept after it ended, for its
    #: permalink; ``None``: forever. The supervisor prunes older ones hourly.
    keep_s: float | None = 30 * 86400.0

    @property
    def scratch(self) -> Path:
        """The directory beside the database where workers draw pictures and record
        videos; emptied when the server starts, so a killed worker leaves nothing."""
        return self.db.with_name(self.db.name + ".scratch")

    def backend(self, name: str | None) -> Backend:
        """The backend a client chose by ``name`` (``None``: the default); :class:`BadInput`
        naming the choices for one the server does not offer."""
        if name is None:
            return self.backends[0]
        for b in self.backends:
            if b.name == name:
                return b
        offered = ", ".join(repr(b.name) for b in self.backends)
        raise BadInput(f"llm: this server offers no backend {name!r}; choose {offered}")


def check_bind(host: str, token: str | None) -> None:
    """:class:`BadInput` for a bind that would expose the service without a token, or a
    token too short to guess slowly."""
    if token is not None and len(token) < MIN_TOKEN_CHARS:
        raise BadInput(f"--token: {len(token)} characters; use at least {MIN_TOKEN_CHARS} "
                       "(e.g. from `python -c 'import secrets; print(secrets.token_urlsafe())'`)")
    if token is None and not is_loopback(host):
        raise BadInput(f"--host {host}: not a loopback address; serving other hosts needs "
                       f"--token (at least {MIN_TOKEN_CHARS} characters)")


def is_loopback(host: str) -> bool:
    """Whether ``host`` names this machine only (127.0.0.0/8, ::1, localhost)."""
    import ipaddress

    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False
