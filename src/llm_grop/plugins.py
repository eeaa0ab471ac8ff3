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
import sys
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from importlib import metadata
from typing import Any, Generic, TypeVar

from llm_grop.errors import BadInput, LLMGropError

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
        protocol: the runtime-checkable protocol an object a factory makes must follow, and
            ``product`` the members it needs, named when one does not.
        check: raises :class:`BadInput` when a loaded object is not a valid entry; it gets
            the entry's name, the object and where it came from.
    """

    group: str
    kind: str
    flag: str
    module: str
    builtins: Mapping[str, str]
    factory: str | None = None
    product: tuple[str, ...] = ()
    protocol: type | None = None
    check: Callable[[str, Any, str], None] | None = None
    _runtime: dict[str, Any] = field(default_factory=dict)
    _loaded: dict[str, Any] = field(default_factory=dict)
    _plugins: dict[str, metadata.EntryPoint] | None = None

    def __post_init__(self) -> None:
        _REGISTRIES[self.group] = self

    @property
    def param(self) -> str:
        """The Python API's parameter that chooses one (``method``), which errors name."""
        return self.flag.removeprefix("--").replace("-", "_")

    def register(self, name: str, entry: T) -> None:
        """Make ``entry`` available as ``name`` in this process (it replaces any other)."""
        key = _normal(name)
        if not key:
            raise BadInput(f"a {self.kind} needs a non-empty name", param=self.param)
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
                elif key in found:
                    log.warning("plugin %s %r from %s is ignored: %s declares it too",
                                self.kind, key, _dist(ep), _dist(found[key]))
                else:
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

        Raises :class:`BadInput` (one line, naming the parameter) for an unknown name or a plugin
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
                raise BadInput(f"plugin {key!r} from {_dist(ep)} failed to load "
                               f"({ep.value}): {type(exc).__name__}: {exc}",
                               param=self.param) from None
            self._validate(key, obj, f"plugin {_dist(ep)}")
            log.debug("loaded %s %r from %s", self.kind, key, _dist(ep))
        self._loaded[key] = obj
        return obj  # type: ignore[no-any-return]

    def key(self, name: str) -> str:
        """The canonical name of an available entry (``" GROP"`` -> ``"grop"``); raises
        :class:`BadInput` for an unknown one."""
        key = _normal(name)
        if key not in self._runtime and key not in self.builtins and key not in self.plugins():
            raise self._unknown(name)
        return key

    def create(self, name: str, *args: Any) -> Any:
        """What the factory registered as ``name`` makes of ``args``.

        A plugin's factory that fails, or makes an object that does not follow
        :attr:`protocol`, is :class:`BadInput` naming the plugin (llm-grop's own errors
        pass).
        """
        key = self.key(name)
        origin = self.origin(key)
        try:
            made = self.get(key)(*args)
        except LLMGropError:
            raise
        except Exception as exc:
            if origin == "llm-grop":
                raise
            raise BadInput(f"{origin}: {self.kind} {key!r} failed to start: "
                           f"{type(exc).__name__}: {exc}", param=self.param) from None
        if self.protocol is not None and not isinstance(made, self.protocol):
            raise BadInput(f"{origin}: {self.kind} {key!r} made an object that does not "
                           f"follow the {self.protocol.__name__} protocol (it needs "
                           f"{', '.join(self.product)})", param=self.param)
        return made

    def _validate(self, name: str, obj: Any, origin: str) -> None:
        if self.factory is not None and not callable(obj):
            raise BadInput(f"{origin}: {self.kind} {name!r} is not a factory "
                           f"{self.factory}", param=self.param)
        if self.check is not None:
            self.check(name, obj, origin)

    def _unknown(self, name: str) -> BadInput:
        return BadInput(f"unknown {self.kind} {name!r} "
                        f"(available: {', '.join(self.names())})", param=self.param)


def _normal(name: str) -> str:
    return name.strip().lower()


def _dist(ep: metadata.EntryPoint) -> str:
    """The distribution that declares ``ep``, for messages."""
    dist = getattr(ep, "dist", None)
    return f"{dist.name} {dist.version}" if dist is not None else ep.value


def registered(used: Mapping[str, Iterable[str]] | None = None
               ) -> dict[str, tuple[str, dict[str, Any]]]:
    """The entries registered at run time, as ``group -> (registry module, entries)``:
    all of them, or only the names ``used`` lists per group.

    Raises :class:`BadInput` when one cannot reach another process: it does not pickle, or
    it was defined in a ``__main__`` that a new process cannot import (``python -c``, a
    notebook). Register it in a module, or declare an entry point.
    """
    out: dict[str, tuple[str, dict[str, Any]]] = {}
    for group, reg in _REGISTRIES.items():
        wanted = None if used is None else {_normal(n) for n in used.get(group, ())}
        entries = {n: e for n, e in reg._runtime.items() if wanted is None or n in wanted}
        for name, entry in entries.items():
            reason = _unportable(entry)
            if reason is not None:
                raise BadInput(f"{reg.kind} {name!r} was registered at run time "
                               f"but cannot reach worker processes ({reason}); define it in "
                               "a module, declare it as an entry point, or use one worker",
                               param=reg.param)
        if entries:
            out[group] = (reg.module, entries)
    return out


def _unportable(entry: Any) -> str | None:
    """Why ``entry`` cannot be sent to a spawned process, or ``None``."""
    main = sys.modules.get("__main__")
    modules = {getattr(entry, "__module__", None), type(entry).__module__}
    if "__main__" in modules and not getattr(main, "__file__", None):
        return "it was defined in an interactive __main__"
    try:
        pickle.dumps(entry)
    except Exception as exc:  # noqa: BLE001 - any pickling failure means the same
        return type(exc).__name__
    return None


def restore(entries: Mapping[str, tuple[str, Mapping[str, Any]]]) -> None:
    """Register again, in this process, what :func:`registered` collected in another."""
    for group, (module, named) in entries.items():
        importlib.import_module(module)
        reg = _REGISTRIES[group]
        for name, entry in named.items():
            reg.register(name, entry)
