"""A content-addressed, on-disk cache of LLM answers, shared by every process on a machine.

An answer is stored under the SHA-256 of everything that decides it: the backend, what it
serves (:func:`backend_identity`: the model, the endpoint or the recorded file), the
prompt, every sampling parameter and the seed, the grammar and the JSON Schema. Identical
calls, made by different methods, trials, bench cells or worker processes, are answered
once. Calls without a seed are never cached: an unseeded call is asked to differ. Neither
are calls to a backend that does not say what its answers depend on
(:func:`backend_identity`). A replay file that holds several answers to one call is
answered with the first it served.

Layout: ``DIR/ab/abcdef....json``, one JSON object per answer (the key's fields and the
call's record). A file is written beside its final name and renamed onto it
(:func:`os.replace`), so concurrent writers on one machine never leave a half-written
answer: a reader sees the whole file or none, and two writers of one key write the same
answer. An entry that does not read back whole, or whose stored key is not the one asked
for, is asked again and rewritten; nothing else is ever rewritten or deleted. Remove the
directory to empty the cache.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import secrets
from collections.abc import Mapping
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from llm_grop.errors import LLMError
from llm_grop.llm.record import LLMCallRecord, open_regular, record_from_dict
from llm_grop.settings import DEFAULTS

log = logging.getLogger(__name__)

#: The cache's directory when neither ``--cache-dir`` nor ``$LLM_GROP_CACHE_DIR`` is given.
DEFAULT_DIR = Path("~/.cache/llm-grop/llm-calls")
#: The environment variable that moves the default directory.
ENV_DIR = "LLM_GROP_CACHE_DIR"
#: Bytes an entry may hold besides its answer: its key, prompt and schema.
_ENTRY_OVERHEAD_BYTES = 4_194_304  # 4 MiB
#: Bumped when the key's meaning changes, so older entries are never read as newer ones.
_FORMAT = 1


def default_dir() -> Path:
    """``$LLM_GROP_CACHE_DIR``, else ``~/.cache/llm-grop/llm-calls``."""
    return Path(os.environ.get(ENV_DIR) or DEFAULT_DIR).expanduser()


def backend_identity(llm: Any) -> str | None:
    """What a backend answers from, for the cache key: its declared ``cache_identity`` (the
    embedded backend names its model file and llama.cpp's version, openai its endpoint
    and model, replay its recording's digest). ``None``, and so no caching, for a backend
    that declares none: a plugin opts in by saying what its answers depend on."""
    own = llm.cache_identity
    return str(own) if own else None


@dataclass(frozen=True)
class CallKey:
    """Everything that decides an LLM's answer; ``digest`` addresses it in the cache."""

    backend: str
    identity: str
    prompt: str
    params: Mapping[str, Any]
    grammar: str | None
    schema: Mapping[str, Any] | None

    @property
    def digest(self) -> str:
        """The SHA-256 (hex) of the key's canonical JSON."""
        text = json.dumps({"format": _FORMAT, **asdict(self)}, sort_keys=True,
                          ensure_ascii=False, separators=(",", ":"))
        return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _plain(data: Any) -> Any:
    """``data`` as it reads back from JSON (tuples become lists)."""
    return json.loads(json.dumps(data, ensure_ascii=False))


class LLMCache:
    """The answers under ``root`` (created on the first write); an answer over
    ``max_answer_bytes`` (bytes of its UTF-8 text) is never served."""

    def __init__(self, root: str | os.PathLike[str],
                 max_answer_bytes: int = DEFAULTS.max_answer_bytes) -> None:
        self.root = Path(root).expanduser()
        self.max_answer_bytes = max_answer_bytes

    def _path(self, key: CallKey) -> Path:
        digest = key.digest
        return self.root / digest[:2] / f"{digest}.json"

    def get(self, key: CallKey) -> LLMCallRecord | None:
        """The answer stored for ``key``, marked ``cached``, or ``None``.

        An entry is served only if it is whole and its stored key is ``key``: a damaged
        entry (a disk error, a truncated file, a hand edit, a ``null`` answer) or one
        copied under another key's name is a miss, with one warning, and the answer asked
        again replaces it. So is anything but a regular file (a FIFO, a device, a symbolic
        link: it is never opened in a way that could block), and an answer over the cap."""
        path = self._path(key)
        try:
            data = json.loads(self._read(path))
            if not isinstance(data, dict):
                raise ValueError("not a JSON object")
            if data.get("key") != _plain(asdict(key)):
                raise ValueError("it was stored for another call")
            record = record_from_dict(data.get("record"), "record")
            if record.prompt != key.prompt:
                raise ValueError("its prompt is another call's")
            if len(record.response.encode("utf-8")) > self.max_answer_bytes:
                raise ValueError(f"its answer is over {self.max_answer_bytes} bytes")
        except FileNotFoundError:
            return None
        except (OSError, ValueError, LLMError) as exc:
            log.warning("LLM cache: ignoring bad entry %s (%s); asking again", path,
                        getattr(exc, "strerror", None) or exc)
            return None
        return replace(record, cached=True)

    def _read(self, path: Path) -> str:
        """The text of the entry at ``path``, which must be a regular file of a bounded
        size: its prompt, its key and an answer within the cap."""
        with open(open_regular(path, os.O_RDONLY, follow=False), "rb") as f:
            # Room for the key (which holds the prompt twice) beside the answer.
            limit = self.max_answer_bytes + _ENTRY_OVERHEAD_BYTES
            data = f.read(limit + 1)
        if len(data) > limit:
            raise ValueError(f"over {limit} bytes")
        return data.decode("utf-8")

    def put(self, key: CallKey, record: LLMCallRecord) -> None:
        """Store ``record`` as the answer to ``key``; a failure to write is logged, never
        raised (the call itself succeeded)."""
        path = self._path(key)
        data = {"key": asdict(key), "record": asdict(replace(record, cached=False))}
        # Not files.jsonio's writer: the LLM layer stands below the files. No fsync: an
        # entry lost to a power cut is only asked again.
        tmp = path.with_name(f".{path.stem}.{os.getpid()}-{secrets.token_hex(4)}.tmp")
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp.write_text(json.dumps(data, ensure_ascii=False), encoding="utf-8")
            os.replace(tmp, path)
        except (OSError, ValueError) as exc:  # ValueError: text UTF-8 cannot hold
            log.warning("LLM cache: cannot write %s (%s)", path,
                        getattr(exc, "strerror", None) or exc)
            tmp.unlink(missing_ok=True)
