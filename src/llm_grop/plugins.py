"""One plugin mechanism for LLM backends, methods and simulators.

Each kind of component has one :class:`Registry`. It holds the entries llm-grop ships,
the entries that installed packages declare as entry points, and entries registered at
run time. Third-party packages add entries the way simonw/llm's plugins do, through an
entry point group in their ``pyproject.toml``::

    [project.entry-points."llm_grop.methods"]
    my-method = "my_package.methods:MY_METHOD"

The name on the left is what users type (``--method my-method``); the object on the right
is imported only when that entry is first used, so a broken plugin never breaks the others.

=========================  ===============================================  ===============
group                      the object                                       chosen with
=========================  ===============================================  ===============
``llm_grop.llm_backends``  a factory ``(BackendOptions) -> LLM``            ``--llm``
``llm_grop.methods``       a :class:`~llm_grop.methods.base.Method`         ``--method``
``llm_grop.simulators``    a factory ``() -> Simulator``                    ``--simulator``
=========================  ===============================================  ===============

Precedence: an entry registered at run time replaces one of the same name; a plugin may not
take a name llm-grop ships (it is skipped, with a warning in the log).

Worker processes find installed entry points again by themselves. Entries registered at
run time live in one process, so the bench hands them to its workers: :func:`registered`
collects them (they must be picklable: defined at module level) and :func:`restore`
registers them again in the worker.
"""

from __future__ import annotations

import importlib
import logging
import pickle
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib import metadata
from typing import Any, Generic, TypeVar

from llm_grop.errors import BadInput

T = TypeVar("T")

log = logging.getLogger(__name__)

#: Every registry made so far, by entry point group.
_REGISTRIES: dict[str, Registry[Any]] = {}


@dataclass
class Registry(Generic[T]):
    """The entries of one kind, by name.

    Attributes:
        group: the entry point group, e.g. ``llm_grop.methods``.
        kind: what an entry is, for messages (``method``).
        flag: the command-line flag that chooses one (``--method``).
        module: the module that defines this registry (imported again in workers).
        builtins: what llm-grop ships: name -> ``"module:attribute"``, loaded on first use.
        factory: for kinds whose entries are factories, their signature (``() -> Simulator``);
            an entry that is not callable is refused.
        check: raises :class:`BadInput` when a loaded object is not a valid entry; it gets
            the entry's name, the object and where it came from.
    """

    group: str
    kind: str
    flag: str
    module: str
    builtins: Mapping[str, str]
    factory: str | None = None
    check: Callable[[str, Any, str], None] | None = None
    _runtime: dict[str, Any] = field(default_factory=dict)
    _loaded: dict[str, Any] = field(default_factory=dict)
    _plugins: dict[str, metadata.EntryPoint] | None = None

    def __post_init__(self) -> None:
        _REGISTRIES[self.group] = self

    def register(self, name: str, entry: T) -> None:
        """Make ``entry`` available as ``name`` in this process (it replaces any other)."""
        key = _normal(name)
        if not key:
            raise BadInput(f"{self.flag}: a {self.kind} needs a non-empty name")
        self._validate(key, entry, "registered at run time")
        self._runtime[key] = entry
        self._loaded.pop(key, None)
        log.debug("registered %s %r at run time", self.kind, key)

    def unregister(self, name: str) -> None:
        """Forget an entry registered at run time (shipped and installed ones stay)."""
        key = _normal(name)
        self._runtime.pop(key, None)
        self._loaded.pop(key, None)

    def plugins(self) -> dict[str, metadata.EntryPoint]:
        """The installed packages' entry points of this group (found once per process)."""
        if self._plugins is None:
            found: dict[str, metadata.EntryPoint] = {}
            for ep in metadata.entry_points(group=self.group):
                key = _normal(ep.name)
                if key in self.builtins:
                    log.warning("plugin %s %r from %s is ignored: llm-grop ships a %s of "
                                "that name", self.kind, key, _dist(ep), self.kind)
                elif key not in found:
                    found[key] = ep
            self._plugins = found
        return self._plugins

    def names(self) -> list[str]:
        """Every available name: shipped ones in their order, then plugins, then run-time."""
        names = dict.fromkeys(self.builtins)
        names.update(dict.fromkeys(sorted(self.plugins())))
        names.update(dict.fromkeys(self._runtime))
        return list(names)

    def origin(self, name: str) -> str:
        """Where the entry ``name`` comes from: ``llm-grop``, ``plugin DIST`` or ``run time``."""
        key = _normal(name)
        if key in self._runtime:
            return "run time"
        if key in self.builtins:
            return "llm-grop"
        ep = self.plugins().get(key)
        if ep is None:
            raise self._unknown(name)
        return f"plugin {_dist(ep)}"

    def get(self, name: str) -> T:
        """The entry called ``name``, imported on first use.

        Raises :class:`BadInput` (one line, naming the flag) for an unknown name or a plugin
        that fails to load.
        """
        key = _normal(name)
        if key in self._runtime:
            return self._runtime[key]  # type: ignore[no-any-return]
        if key in self._loaded:
            return self._loaded[key]  # type: ignore[no-any-return]
        if key in self.builtins:
            module, _, attr = self.builtins[key].partition(":")
            obj = getattr(importlib.import_module(module), attr)
        else:
            ep = self.plugins().get(key)
            if ep is None:
                raise self._unknown(name)
            try:
                obj = ep.load()
            except Exception as exc:  # noqa: BLE001 - a plugin's failure is the user's input
                raise BadInput(f"{self.flag}: plugin {key!r} from {_dist(ep)} failed to load "
                               f"({ep.value}): {type(exc).__name__}: {exc}") from None
            self._validate(key, obj, f"plugin {_dist(ep)}")
            log.debug("loaded %s %r from %s", self.kind, key, _dist(ep))
        self._loaded[key] = obj
        return obj  # type: ignore[no-any-return]

    def _validate(self, name: str, obj: Any, origin: str) -> None:
        if self.factory is not None and not callable(obj):
            raise BadInput(f"{self.flag}: {origin}: {self.kind} {name!r} is not a factory "
                           f"{self.factory}")
        if self.check is not None:
            self.check(name, obj, origin)

    def _unknown(self, name: str) -> BadInput:
        return BadInput(f"{self.flag}: unknown {self.kind} {name!r} "
                        f"(available: {', '.join(self.names())})")


def _normal(name: str) -> str:
    return name.strip().lower()


def _dist(ep: metadata.EntryPoint) -> str:
    """The distribution that declares ``ep``, for messages."""
    dist = getattr(ep, "dist", None)
    return f"{dist.name} {dist.version}" if dist is not None else ep.value


def registered() -> dict[str, tuple[str, dict[str, Any]]]:
    """Every entry registered at run time, as ``group -> (registry module, entries)``.

    Raises :class:`BadInput` when one cannot be sent to another process (it is not
    defined at module level); register it in a module, or declare an entry point.
    """
    out: dict[str, tuple[str, dict[str, Any]]] = {}
    for group, reg in _REGISTRIES.items():
        for name, entry in reg._runtime.items():
            try:
                pickle.dumps(entry)
            except Exception as exc:  # noqa: BLE001 - any pickling failure means the same
                raise BadInput(f"{reg.flag}: {reg.kind} {name!r} was registered at run time "
                               f"but cannot reach worker processes ({type(exc).__name__}); "
                               "define it at module level, declare it as an entry point, "
                               "or use one worker") from None
        if reg._runtime:
            out[group] = (reg.module, dict(reg._runtime))
    return out


def restore(entries: Mapping[str, tuple[str, Mapping[str, Any]]]) -> None:
    """Register again, in this process, what :func:`registered` collected in another."""
    for group, (module, named) in entries.items():
        importlib.import_module(module)
        reg = _REGISTRIES[group]
        for name, entry in named.items():
            reg.register(name, entry)


def registries() -> dict[str, Registry[Any]]:
    """Every registry made so far, by entry point group."""
    return dict(_REGISTRIES)
