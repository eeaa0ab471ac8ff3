"""Cutting an LLM's answer into tokens: source lines, sentences, words, and the object
mentions and relation phrases among the words (the first half of
:mod:`llm_grop.language.answer_reader`, whose docstring says how an answer is read).

Tokenising is stateless: a sentence's tokens depend only on its words, the requested
items and the catalog. Every step is linear in the length of the text, so that a
megabyte-long answer is read in a fraction of a second.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import NamedTuple

from llm_grop.language.vocabulary import ARTICLES, expand_its, phrase_table
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog, ObjectSpec, normalize_name, singular_forms

#: The leading words :func:`~llm_grop.world.catalog.normalize_name` drops ("one fork").
_NAME_ARTICLES = frozenset({"the", "a", "an", "one", "some", "another"})
_NEGATIONS = frozenset({"not", "never", "don't", "dont", "doesn't", "shouldn't", "avoid",
                        "cannot", "can't", "mustn't", "isn't", "nor", "instead"})
_PRONOUNS = frozenset({"it", "its", "it's"})
#: Most words an object mention may have ("dinner fork 2", "bread and butter plate").
MAX_OBJECT_WORDS = 5
_WORD_KINDS = {"and": "and", "&": "and", "with": "with", "which": "which", "that": "which",
               **{w: "pron" for w in _PRONOUNS}, **{w: "neg" for w in _NEGATIONS}}

#: Kinds of token that name an object: requested ("obj") or not ("foreign").
THINGS = ("obj", "foreign")


# One or more numberings, bullets and labels at the start of a line, taken in one match
# (removing them one at a time copied the rest of the line each time: quadratic).
_NUMBERING = re.compile(
    r"^(?:\s*(?:(?:step|example|answer|action)\s*\d*\s*[:.)-]?|\(?\d+\s*[.):-]|"
    r"\(?[a-z][.)](?=\s)|[-•+*>]|a:)\s*)+", re.IGNORECASE)
_SENTENCES = re.compile(r"(?<=[.!?;])\s+(?=\S)")
_MARKDOWN = re.compile(r"[*_`#|]+")
_SPACES = re.compile(r"\s+")
_SPACE_BEFORE_PUNCTUATION = re.compile(r"\s+([,.:;!?])")
_NOT_WORD = re.compile(r"[^a-z0-9' ]+")


class Tok(NamedTuple):
    """A token of a sentence: an object mention, a relation phrase, "and", "it", a negation.

    ``pos`` is the index of its first word in the sentence and ``end`` the index after its
    last word.
    """

    kind: str  # "obj", "foreign", "rel", "and", "pron", "neg", "with", "which"
    value: str = ""
    plural: bool = False
    bare: bool = False
    pos: int = 0
    end: int = 0


def clean(line: str) -> str:
    """``line`` without markdown, leading numbering or bullets, and with single spaces."""
    line = _NUMBERING.sub("", _MARKDOWN.sub(" ", line), count=1)
    return _SPACE_BEFORE_PUNCTUATION.sub(r"\1", _SPACES.sub(" ", line)).strip()


def sentences(line: str) -> list[str]:
    """A cleaned line's sentences, each cleaned again (numbering may start a sentence)."""
    # A cleaned line has no markdown, no runs of spaces and no space before punctuation,
    # so cleaning one of its sentences only takes off the numbering.
    return [_NUMBERING.sub("", s, count=1) for s in _SENTENCES.split(line)]


def words(sentence: str) -> list[str]:
    """A sentence's words: lower case, ASCII letters, digits and "'", no articles."""
    text = sentence.lower().replace("’", "'").replace("-", " ").replace("–", " ")
    text = _NOT_WORD.sub(" ", text)
    kept = [w.strip("'") for w in text.split() if w.strip("'")]
    return [w for w in expand_its(kept) if w not in ARTICLES]


class Tokenizer:
    """Finds the requested objects, other catalog objects and relation phrases in words.

    Lookups go through the catalog (:meth:`Catalog.lookup`) only for word runs that can
    name an object at all: every catalog name's words but the last must match, and the
    last one must be a form of a catalog name's last word.
    """

    def __init__(self, items: Sequence[Item], catalog: Catalog) -> None:
        self.catalog = catalog
        self.kinds = {it.kind for it in items}
        self.aliases = catalog.aliases()
        self.table = phrase_table()
        instances = {it.name for it in items}
        # Instances matched as written ("dinner fork 2"); a kind's name is looked up.
        self._instances = {tuple(n.split()): n for n in instances
                           if n not in self.kinds and n == " ".join(n.split())}
        self._instance_firsts = {t[0] for t in self._instances if t}
        split = [a.split() for a in self.aliases]
        self._heads = {tuple(s[:-1]) for s in split if s}
        self._head_prefixes = {h[:k] for h in self._heads for k in range(len(h) + 1)}
        self._lasts = {s[-1] for s in split if s}
        # Words that may start an object mention besides a form of a name's last word.
        self._starters = (_NAME_ARTICLES | self._instance_firsts
                          | {h[0] for h in self._heads if h})
        # Caches over one answer, whose words and sentences often repeat.
        self._last_ok: dict[str, bool] = {}
        self._specs: dict[str, tuple[ObjectSpec, bool] | None] = {}
        self._sentences: dict[str, list[Tok]] = {}
        self._windows: dict[tuple[str, ...], Tok | None] = {}

    def sentence_tokens(self, sentence: str) -> list[Tok]:
        """The tokens of one of :func:`sentences` (the list is shared: do not change it)."""
        toks = self._sentences.get(sentence)
        if toks is None:
            toks = self._sentences[sentence] = self.tokens(words(sentence))
        return toks

    def tokens(self, words: list[str]) -> list[Tok]:
        """The tokens of one sentence's ``words``; other words are skipped."""
        out: list[Tok] = []
        table = self.table
        i = 0
        while i < len(words):
            # Most words start nothing; two set lookups tell (the same tests as _lengths's
            # and _phrase_at's first ones).
            word = words[i]
            hit = None
            if word in self._starters or self._is_last(word):
                hit = self._object_at(words, i)
            if hit is None and table.starts(word):
                hit = self._phrase_at(words, i)
            if hit is not None:
                out.append(hit)
                i = hit.end
                continue
            kind = _WORD_KINDS.get(words[i])
            if kind is not None:
                out.append(Tok(kind, pos=i, end=i + 1))
            i += 1
        return out

    def _is_last(self, word: str) -> bool:
        """Whether a form of ``word`` ends a catalog name (cached: one answer's words)."""
        ok = self._last_ok.get(word)
        if ok is None:
            ok = self._last_ok[word] = any(f in self._lasts for f in singular_forms(word))
        return ok

    def _lengths(self, words: Sequence[str], i: int, limit: int) -> set[int]:
        """Word counts ``n`` for which ``words[i:i + n]`` may name an object: a superset
        of those :meth:`_object_at` accepts, found without building every run."""
        out: set[int] = set()
        if words[i] in self._instance_firsts:
            out.update(n for n in range(1, limit + 1)
                       if tuple(words[i:i + n]) in self._instances)
        start = i
        if words[i] in _NAME_ARTICLES:
            # Alone it is looked up as it is; before other words normalize_name drops it.
            if () in self._heads and self._is_last(words[i]):
                out.add(1)
            start = i + 1
        head: tuple[str, ...] = ()
        for k in range(start, i + limit):
            if head in self._heads and self._is_last(words[k]):
                out.add(k + 1 - i)
            head += (words[k],)
            if head not in self._head_prefixes:
                break
        return out

    def _lookup(self, text: str) -> tuple[ObjectSpec, bool] | None:
        """The spec ``text`` names and whether it is a plural, else ``None``."""
        if text not in self._specs:
            spec = self.catalog.lookup(text)
            self._specs[text] = None if spec is None else (
                spec, normalize_name(text) not in self.aliases)
        return self._specs[text]

    def _object_at(self, words: list[str], i: int) -> Tok | None:
        """The longest object mention starting at ``words[i]``."""
        # It depends on the next MAX_OBJECT_WORDS words only, which often repeat.
        window = tuple(words[i:i + MAX_OBJECT_WORDS])
        if window in self._windows:
            hit = self._windows[window]
        else:
            hit = self._windows[window] = self._object_in(window)
        return None if hit is None else Tok(hit.kind, hit.value, hit.plural, hit.bare, i,
                                            i + hit.end)

    def _object_in(self, window: tuple[str, ...]) -> Tok | None:
        """The longest object mention at the start of ``window`` (``end``: its length)."""
        for n in sorted(self._lengths(window, 0, len(window)), reverse=True):
            if window[:n] in self._instances:
                return Tok("obj", self._instances[window[:n]], end=n)
            text = " ".join(window[:n])
            found = self._lookup(text)
            if found is not None:
                spec, plural = found
                kind = "obj" if spec.name in self.kinds else "foreign"
                return Tok(kind, spec.name, plural, end=n)
        return None

    def _phrase_at(self, words: list[str], i: int) -> Tok | None:
        """The longest relation phrase starting at ``words[i]``, skipped words passed over."""
        m = self.table.match(words, i)
        return None if m is None else Tok("rel", m.relation, bare=m.bare, pos=i, end=m.end)
