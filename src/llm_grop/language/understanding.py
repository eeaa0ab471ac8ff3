"""Understanding a request in people's own words: the catalog matcher when it reads every
word, else the configured LLM reads the whole request.

* **The fast path.** :func:`~llm_grop.language.request.read_request` reads the request
  alone only when it accounts for every word (catalog names, counts, fillers, relation
  phrases) and resolves every reference. Then no LLM is asked.
* **The LLM reads the rest.** Otherwise the LLM reads the whole request in one call (seed
  stage ``llm.reading``), with the catalog's names in the prompt; see
  :mod:`llm_grop.language.llm_reading` for the grammar, the schema and the answer's
  reader. Without an LLM (``llm=None``) such a request is refused with the first chunk the
  matcher could not read, with suggestions.
* **The gate.** A request with no word that may stand for tableware at all (no catalog
  word or a misspelling of one, no word of ``dining_words.yaml``: "hello there",
  "happiness") is refused before any call. Any other word never refuses a request
  before the LLM is asked.
* **Guesses.** An object the LLM chose that the request does not name ("coffee" read as a
  mug, "breakfast" as a plate and a mug), or whose number the request does not give
  ("some strawberries"), is marked ``source="llm"`` and printed as one warning line; a
  typo of a catalog name ("frok") counts as naming it. ``guess=False`` refuses such a
  reading (and a request naming no object before any call). A relation the LLM reads is
  kept only when the request states it (:func:`keep_stated`).
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

from llm_grop import seeds
from llm_grop.errors import BadInput
from llm_grop.language.llm_reading import (
    NothingRead,
    read_reading_answer,
    reading_grammar,
    reading_prompt,
    reading_schema,
)
from llm_grop.language.parts import Unread
from llm_grop.language.reading import Reading, ReadObject, to_request
from llm_grop.language.request import EXAMPLE, FastReading, read_request
from llm_grop.language.vocabulary import ARTICLES, dining_words, request_words
from llm_grop.language.words import normalized, tokens
from llm_grop.llm.base import CallLog, SamplingParams
from llm_grop.world.catalog import Catalog, singular_forms
from llm_grop.world.llmlog import CallRecord
from llm_grop.world.request import Request

_WORD = re.compile(r"[^\W\d_]+")
#: A misspelt name is at least this close to a catalog name (difflib's ratio).
TYPO_RATIO = 0.75


def _catalog_words(catalog: Catalog) -> frozenset[str]:
    """The words of the catalog's names and synonyms that say something: "and" and "of"
    ("bread and butter plate", "slice of bread") and the like name no tableware."""
    vocab = request_words()
    glue = {p[0] for p in (*vocab.fillers, *vocab.separator_words, *vocab.counts)
            if len(p) == 1} | set(ARTICLES)
    return frozenset(w for alias in catalog.aliases() for w in alias.split() if w not in glue)


def may_name_tableware(text: str, catalog: Catalog) -> bool:
    """Whether a word of ``text`` may stand for tableware (see the module docstring)."""
    known = dining_words().every | _catalog_words(catalog)
    return any(form in known for word in _WORD.findall(normalized(text).lower())
               for form in singular_forms(word))


def misspelt(unread: Sequence[Unread], catalog: Catalog) -> frozenset[str]:
    """The catalog kinds an unread chunk misspells: a run of its words as close as
    :data:`TYPO_RATIO` to a name or synonym of as many words ("frok", "plait")."""
    out: set[str] = set()
    for alias, kind in catalog.aliases().items():
        n = len(alias.split())
        for chunk in unread:
            words = chunk.text.split()
            for i in range(len(words) - n + 1):
                run = " ".join(words[i:i + n])
                if difflib.SequenceMatcher(None, run, alias).ratio() >= TYPO_RATIO:
                    out.add(kind)
    return frozenset(out)


def mark_guesses(reading: Reading, fast: FastReading, catalog: Catalog) -> Reading:
    """``reading`` (the LLM's) with each object's ``source``: ``"request"`` when the request
    names it (or misspells it) and gives its number, ``"llm"`` when the LLM chose it or how
    many."""
    typos = misspelt(fast.unread, catalog)
    read: dict[str, int] = {}
    for o in reading.objects:
        read[o.name] = read.get(o.name, 0) + o.count
    objects = []
    for o in reading.objects:
        counts = fast.named.get(o.name)
        # The request's own number must agree with the LLM's ("a plate" is not 4 plates).
        # ("two plates ... for two people" is one plate each.)
        named = (counts is not None and all(counts) and (
            read[o.name] in (sum(counts), max(counts))
            or read[o.name] * reading.diners == sum(counts))) or (
            counts is None and o.name in typos)
        objects.append(replace(o, source="request" if named else "llm"))
    return replace(reading, objects=tuple(objects))


def keep_stated(reading: Reading, text: str) -> tuple[Reading, list[str]]:
    """``reading`` without the relations the request does not state, and one warning that
    lists them: a relation's quoted words must be words of ``text`` in the order written
    there, and one without words must relate objects the request names (a weak model
    copies relations from elsewhere)."""
    said = [t.word for t in tokens(text)]
    named = {o.name for o in reading.objects if o.source == "request"}
    kept, ignored = [], []
    for r in reading.relations:
        quoted = [t.word for t in tokens(r.words) if t.word not in (",", ".", "-")]
        objects = [n for n in (r.subject, r.reference, r.partner) if n is not None]
        rest = iter(said)
        if quoted and all(w in rest for w in quoted) or not quoted and all(
                re.sub(r" [0-9]+$", "", n) in named for n in objects):
            kept.append(r)
        else:
            ignored.append(f"{r.subject} {r.relation} {r.reference or 'the table'}")
    notes = [f"ignored the LLM's relation(s) the request does not state: "
             f"{', '.join(dict.fromkeys(ignored))}"] if ignored else []
    return replace(reading, relations=tuple(kept)), notes


def guess_warning(objects: Sequence[ReadObject], backend: str) -> str:
    """The one warning line that lists what the LLM chose."""
    chosen = ", ".join(f"{o.count} {o.name}" + (f" (for {o.words!r})" if o.words else "")
                       for o in objects)
    return (f"the {backend} LLM chose what the request does not say: {chosen}; "
            "guess=False refuses this")


@dataclass(frozen=True)
class LLMReading:
    """The LLM's reading of a request (guesses marked, relations it does not state
    dropped), the warnings it gives, and the call that read it."""

    reading: Reading
    warnings: tuple[str, ...]
    record: CallRecord


def read_with_llm(fast: FastReading, catalog: Catalog, log: CallLog, seed: int = 0,
                  params: SamplingParams | None = None,
                  say: Callable[[str], None] | None = None) -> LLMReading:
    """The LLM ``log``'s reading of the request the matcher read as ``fast`` (seed stage
    ``llm.reading``). Raises :class:`BadInput` when its answer names nothing or does not
    check (:func:`~llm_grop.language.llm_reading.read_reading_answer`)."""
    if say is not None:
        say(f"asking {log.model} to read the request")
    where = f"request: the {log.backend} LLM's reading"
    record = log.complete(reading_prompt(fast.text, catalog),
                          (params or SamplingParams()).with_seed(
                              seeds.int_seed(seed, "llm.reading")),
                          reading_grammar(catalog), schema=reading_schema(catalog))
    try:
        reading, dropped = read_reading_answer(record.response, fast.text, catalog, where)
    except NothingRead:
        raise BadInput(f"request: the {log.backend} LLM read no object in {fast.text!r}; "
                       f"name the objects to set, {EXAMPLE}") from None
    warnings = list(dropped)
    if fast.diners > 1 and reading.diners != fast.diners:
        # The request's own diner phrase ("for two") wins over the LLM's number.
        if reading.diners != 1:
            warnings.append(f"the request sets the table for {fast.diners}; the "
                            f"{log.backend} LLM read {reading.diners} diners")
        reading = replace(reading, diners=fast.diners)
    reading = mark_guesses(reading, fast, catalog)
    reading, unstated = keep_stated(reading, fast.text)
    warnings += unstated
    kinds = list(dict.fromkeys(o.name for o in reading.objects))
    left_out = [kind for kind in fast.named if kind not in kinds]
    if fast.named and len(left_out) == len(fast.named):
        raise BadInput(f"request: the {log.backend} LLM's reading ({', '.join(kinds)}) leaves "
                       f"out everything {fast.text!r} names ({', '.join(left_out)}); name "
                       "the objects to set in other words, or use a stronger model")
    if left_out:
        warnings.append(f"the {log.backend} LLM's reading leaves out what the request names: "
                        f"{', '.join(left_out)}")
    chosen = [o for o in reading.objects if o.source == "llm"]
    warnings += [guess_warning(chosen, log.backend)] if chosen else []
    return LLMReading(reading, tuple(warnings), record)


def understand(text: str, catalog: Catalog, llm: CallLog | Callable[[], CallLog] | None,
               seed: int = 0, params: SamplingParams | None = None,
               say: Callable[[str], None] | None = None, guess: bool = True) -> Request:
    """The request ``text`` makes: the matcher's reading when it reads every word, else the
    LLM's (``llm=None``: such a request is refused; a callable makes the LLM only when one
    is needed). ``guess=False`` refuses a reading with objects the request does not name.

    Raises :class:`~llm_grop.errors.BadInput` (one line, exit 2) for a request no reader
    can take, and :class:`~llm_grop.errors.UnknownObject` for a chunk the matcher cannot
    read without an LLM, or a name outside the catalog in the LLM's answer.
    """
    fast = read_request(text, catalog)
    if fast.reading is not None:
        return to_request(fast.reading, catalog)
    typos = misspelt(fast.unread, catalog) if llm is not None else frozenset()
    if llm is None or not (may_name_tableware(fast.text, catalog) or typos):
        raise fast.error()
    if not guess and not fast.named and not typos:
        raise BadInput(f"nothing in {fast.text!r} names an object, and guess=False "
                       f"forbids the LLM to choose them; name the objects to set, {EXAMPLE}",
                       param="request", mentions=("guess",))
    log = llm if isinstance(llm, CallLog) else llm()
    read = read_with_llm(fast, catalog, log, seed, params, say)
    chosen = [o for o in read.reading.objects if o.source == "llm"]
    if chosen and not guess:
        listed = ", ".join(f"{o.count} {o.name}" for o in chosen)
        raise BadInput(f"the {log.backend} LLM chose what {fast.text!r} does not "
                       f"say ({listed}), and guess=False forbids it; name the objects to set",
                       param="request", mentions=("guess",))
    return to_request(read.reading, catalog, (read.record,), read.warnings)


__all__ = ["LLMReading", "guess_warning", "keep_stated", "mark_guesses",
           "may_name_tableware", "misspelt", "read_with_llm", "understand"]
