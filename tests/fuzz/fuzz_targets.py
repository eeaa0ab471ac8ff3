"""How the fuzzers call every text parser, and the property each must keep (shared by
the Hypothesis tests in ``tests/fuzz`` and by ``benchmarks/fuzz.py``).

Each :class:`Target` runs one parser on one input. The property is the same for all: the
parser returns, or raises one of the project's own errors
(:class:`~llm_grop.errors.LLMGropError`) with a one-line message; any other exception,
or a broken invariant (an ``AssertionError``), is a bug.
"""

from __future__ import annotations

import math
import random
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from fuzz_inputs import CATALOG, ITEMS, Input, file_input, text_input

from llm_grop.arrangement.distances import DEFAULT_EDGE_GAP_CM, MAX_GAP_CM, parse_distance_m
from llm_grop.arrangement.preferences import (
    load_preference_file,
    read_edge_preferences,
    read_preferences,
    stated_gaps,
)
from llm_grop.errors import LLMGropError
from llm_grop.files.scene_file import load_scene, parse_scene
from llm_grop.language.answer_reader import parse_relations
from llm_grop.language.llm_reading import read_reading_answer
from llm_grop.language.reading import item_names
from llm_grop.language.request import parse_request, read_request
from llm_grop.llm.record import LLMCallRecord, append_record, load_records
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import MAX_COUNT
from llm_grop.world.table import Table

TABLE = Table()
#: Longest an ignored answer line may be once shortened, and most entries (20 + a count).
MAX_IGNORED_CHARS = 120
MAX_IGNORED_ENTRIES = 21


def _text(data: Input) -> str:
    assert isinstance(data, str), "text parsers are fed text"
    return data


def _request(data: Input) -> None:
    fast = read_request(_text(data), CATALOG)
    assert (fast.reading is None) == bool(fast.unread or fast.doubts), fast
    if fast.reading is None:
        return
    request = parse_request(_text(data), CATALOG)
    names = {it.name for it in request.items}
    assert all(r.subject in names and r.reference in names | {None}
               for r in request.relations), request.relations
    assert all(r.subject in names and r.reference in names
               for c in request.choices for o in c.options for r in o), request.choices


def _answer(data: Input) -> None:
    parsed = parse_relations(_text(data), ITEMS, CATALOG)
    assert len(parsed.ignored) <= MAX_IGNORED_ENTRIES, len(parsed.ignored)
    assert all(len(line) <= MAX_IGNORED_CHARS for line in parsed.ignored), parsed.ignored


def _reading_answer(data: Input) -> None:
    reading, notes = read_reading_answer(_text(data), "a request", CATALOG)
    assert all("\n" not in note for note in notes), notes
    assert reading.objects and 1 <= reading.diners <= 12, reading
    assert all(o.name in CATALOG.specs and 1 <= o.count <= MAX_COUNT
               for o in reading.objects), reading.objects
    names = set(item_names(reading.objects, CATALOG))
    assert all(r.subject in names and r.reference in names | {None}
               and (r.distance_cm is None or r.distance_cm >= 0)
               for r in reading.relations), reading.relations


def _distance(data: Input) -> None:
    for default in (3.0, DEFAULT_EDGE_GAP_CM):
        metres, defaulted = parse_distance_m(_text(data), default)
        assert math.isfinite(metres) and 0.0 <= metres <= MAX_GAP_CM / 100, metres
        assert not defaulted or metres == default / 100, (metres, defaulted)


def _sentences(data: Input) -> tuple[list[str], list[str]]:
    """``(required, pool)``: the first line is required, the others are the pool."""
    lines = [s for s in _text(data).splitlines() if s.strip()]
    return lines[:1], lines[1:]


def _preferences(data: Input) -> None:
    required, pool = _sentences(data)
    prefs = read_preferences(required, pool, ITEMS, CATALOG)
    stated_gaps([*prefs.relations, *(r for c in prefs.choices for o in c.options for r in o)],
                TABLE)


def _edge_preferences(data: Input) -> None:
    required, pool = _sentences(data)
    for metres in read_edge_preferences(required, pool, ITEMS, CATALOG, TABLE).values():
        assert 0.0 <= metres <= TABLE.depth, metres


class _Scratch:
    """One temporary file, rewritten for each input of the file parsers that only read
    files."""

    def __init__(self) -> None:
        self._dir: tempfile.TemporaryDirectory[str] | None = None

    def write(self, data: Input, name: str) -> Path:
        if self._dir is None:
            self._dir = tempfile.TemporaryDirectory(prefix="llm-grop-fuzz-")
        path = Path(self._dir.name) / name
        path.write_bytes(data if isinstance(data, bytes) else data.encode("utf-8"))
        return path


_SCRATCH = _Scratch()


def _catalog(data: Input) -> None:
    if isinstance(data, str):
        Catalog.from_text(data, "fuzz.yaml")
    else:
        Catalog.load([_SCRATCH.write(data, "catalog.yaml")], use_env=False)


def _scene(data: Input) -> None:
    if isinstance(data, str):
        parse_scene(data, "fuzz.yaml")
    else:
        load_scene(_SCRATCH.write(data, "scene.yaml"))


def _replay(data: Input) -> None:
    for record in load_records(_SCRATCH.write(data, "calls.jsonl")):
        assert isinstance(record.response, str)


def _record_round_trip(data: Input) -> None:
    """A call recorded with ``data`` as its response (and model and prompt) reads back
    unchanged: the replay file must hold any text an LLM may answer."""
    text = _text(data)
    record = LLMCallRecord("fuzz", text[:20], text[::-1], text, 0.25, len(text), None, 7)
    path = _SCRATCH.write(b"", "round_trip.jsonl")
    append_record(path, record)
    assert load_records(path) == [record], text


def _preference_file(data: Input) -> None:
    sentences = load_preference_file(_SCRATCH.write(data, "preferences.yaml"))
    assert all(isinstance(s, str) and s for s in sentences)


@dataclass(frozen=True)
class Target:
    """One parser: ``run`` parses an input; ``sample`` draws one from a random stream."""

    name: str
    run: Callable[[Input], None]
    sample: Callable[[random.Random], Input]


def _text_target(name: str, run: Callable[[Input], None], kind: str) -> Target:
    return Target(name, run, lambda rng: text_input(rng, kind))


TARGETS: dict[str, Target] = {t.name: t for t in (
    _text_target("request", _request, "request"),
    _text_target("answer", _answer, "answer"),
    _text_target("reading_answer", _reading_answer, "reading"),
    _text_target("distance", _distance, "distance"),
    _text_target("preferences", _preferences, "preferences"),
    _text_target("edge_preferences", _edge_preferences, "edge"),
    Target("catalog", _catalog, lambda rng: file_input(rng, "catalog")),
    Target("scene", _scene, lambda rng: file_input(rng, "scene")),
    Target("replay", _replay, lambda rng: file_input(rng, "replay")),
    _text_target("record_round_trip", _record_round_trip, "answer"),
    Target("preference_file", _preference_file, lambda rng: file_input(rng, "preference_file")),
)}


def check(target: Target, data: Input) -> BaseException | None:
    """Runs ``target`` on ``data``: ``None`` when it returned or raised a project error
    with a one-line message, else the unexpected exception."""
    try:
        target.run(data)
    except LLMGropError as exc:
        message = str(exc)
        if not message.strip() or len(message.splitlines()) != 1:
            error = AssertionError(f"{type(exc).__name__} message is not one line: {message!r}")
            error.__cause__ = exc
            return error
    except Exception as exc:
        return exc
    return None
