"""Reading spatial relations out of an LLM's free text (the parser behind
:func:`llm_grop.arrangement.relations.parse_relations`).

How an answer is read:

* It works line by line, and within a line sentence by sentence. Numbering
  ("1.", "1)", "Step 2:"), bullets ("-", "*", "•"), markdown, articles and
  capitals are ignored. ``Relation.line`` and ``ParsedAnswer.ignored`` hold the
  source line stripped of surrounding space, numbering, bullets and markdown
  ("2. **Place the fork** left of the plate." -> "Place the fork left of the plate.").
* Objects are found through the catalog (names, synonyms, plurals: "fork" is
  the dinner fork, "teacup" the mug, "coaster" the mug mat), longest first.
  Catalog objects that were not requested are *unrequested*.
* Relation phrases come from ``prompts/relation_phrases.yaml`` (paraphrases such
  as "on the left-hand side of", "behind", "in front of", "in" for "on top of").
* Forms read: ``S <rel> R``; ``S1 and S2 <rel> R`` (each subject); ``S <rel> R
  and T <rel2> U`` (several on one line); ``S <rel> R and T <rel2>`` (T shares
  the line's last reference: "the fork to the left of the plate and the knife
  to the right"); ``S <rel> and T <rel2> R`` (S shares the next one: "the fork
  on the left and the knife on the right of the plate"); ``<rel> R, place S``
  ("To the left of the plate, place the fork"); ``S in the center (of the
  table)``. A phrase right after a reference (at most three words later) is
  about the same subject: ``S <rel> R, <rel2> U`` ("the cup to the upper right
  of the plate, above the knife") and ``S <rel> R, <rel2> (it)`` ("to the left
  of the fork, slightly above it"), unless "which"/"that" makes R its subject
  ("the bread on the bread plate, which sits above the fork").
* Phrases that name no reference ("on the left", "in the upper right"; the
  ``bare`` section of the phrase table) take the line's last reference or the
  next one stated, never the object that follows them; "in"/"on" with no
  object after them are prose, not stacking.
* Several phrases before one reference combine ("above and slightly to the
  right of" is "above and to the right of"; "in a position to the right of" is
  "to the right of"), and so do a horizontal and a vertical relation between
  the same two objects on one line.
* "it"/"its" as a reference is the last reference of the answer so far, else
  the last object related ("to the left of it", "to its left"). In a "with"
  clause ("..., with the bread on it") it is ambiguous, and the relation is
  dropped.
* A relation preceded by a negation ("do not place the fork ...", "the fork
  should not be ...") is dropped, as are self-relations and relations with an
  unrequested object. Lines from which something was dropped, and lines that
  name an object but yield no relation, are returned as ignored lines; lines
  naming no object ("Sure! Here is a typical arrangement:") are not.
* Instances: when items share a kind ("dinner fork", "dinner fork 2"), a
  mention of the kind as a subject is the first instance not yet used as a
  subject in this answer (a plural mention, "the forks", is every such
  instance); as a reference it is the first instance that is not a subject of
  the same relation ("one fork to the left of the other fork"). "dinner fork
  2" is matched as written.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from importlib import resources

import yaml

from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog, normalize_name
from llm_grop.world.relation import CENTER, DIRECTION, RELATION_NAMES, STACKING, Relation

_ARTICLES = frozenset({"the", "a", "an"})
_NEGATIONS = frozenset({"not", "never", "don't", "dont", "doesn't", "shouldn't", "avoid",
                        "cannot", "can't", "mustn't", "isn't", "nor", "instead"})
_PRONOUNS = frozenset({"it", "its", "it's"})
_MAX_OBJECT_WORDS = 5
_WORD_KINDS = {"and": "and", "&": "and", "with": "with", "which": "which", "that": "which",
               **{w: "pron" for w in _PRONOUNS}, **{w: "neg" for w in _NEGATIONS}}
#: Most words between a reference and a phrase that continues its clause
#: ("the plate, slightly above ..."), so far-off prose does not.
_MAX_FOLLOW_GAP = 3


@dataclass(frozen=True)
class _PhraseTable:
    """Phrase (as words) -> (relation name, whether it is bare: takes no reference)."""

    phrases: dict[tuple[str, ...], tuple[str, bool]]
    fillers: frozenset[str]
    longest: int


@functools.lru_cache(maxsize=1)
def _phrase_table() -> _PhraseTable:
    data = yaml.safe_load(resources.files("llm_grop.arrangement").joinpath(
        "prompts/relation_phrases.yaml").read_text("utf-8"))
    phrases: dict[tuple[str, ...], tuple[str, bool]] = {}
    for section, bare in (("relations", False), ("bare", True)):
        for relation, texts in data[section].items():
            if relation not in RELATION_NAMES:
                raise ValueError(f"relation_phrases.yaml: {section}: unknown relation "
                                 f"{relation!r}")
            for text in texts:
                phrases.setdefault(tuple(str(text).split()), (relation, bare))
    return _PhraseTable(phrases, frozenset(data.get("fillers", ())),
                        max(len(p) for p in phrases))


_NUMBERING = re.compile(
    r"^\s*(?:(?:step|example|answer|action)\s*\d*\s*[:.)-]?|\(?\d+\s*[.):-]|\(?[a-z][.)](?=\s)|"
    r"[-•+*>]|a:)\s*", re.IGNORECASE)
_SENTENCES = re.compile(r"(?<=[.!?;])\s+(?=\S)")
_ITS = re.compile(r"\b(?:to|on|at)\s+(?:the\s+)?its\s+(left|right|upper left|upper right|"
                  r"lower left|lower right)(?:\s+hand)?(?:\s+side)?\b")


@dataclass(frozen=True)
class _Tok:
    """A token of a sentence: an object mention, a relation phrase, "and", "it", a negation."""

    kind: str  # "obj", "foreign", "rel", "and", "pron", "neg", "with", "which"
    value: str = ""
    plural: bool = False
    bare: bool = False
    pos: int = 0  # index of the token's first word in the sentence
    end: int = 0  # index after its last word


def _clean(line: str) -> str:
    line = re.sub(r"[*_`#|]+", " ", line)
    previous = None
    while previous != line:
        previous, line = line, _NUMBERING.sub("", line, count=1)
    return re.sub(r"\s+([,.:;!?])", r"\1", re.sub(r"\s+", " ", line)).strip()


def _words(sentence: str) -> list[str]:
    text = sentence.lower().replace("’", "'").replace("-", " ").replace("–", " ")
    text = _ITS.sub(lambda m: f"to the {m.group(1)} of it", text)
    text = re.sub(r"[^a-z0-9' ]+", " ", text)
    return [w.strip("'") for w in text.split() if w not in _ARTICLES and w.strip("'")]


class _Reader:
    """Tokenises sentences and keeps the state of one answer (subjects used, history)."""

    def __init__(self, items: Sequence[Item], catalog: Catalog) -> None:
        self.catalog = catalog
        self.instances = {it.name for it in items}
        self.by_kind: dict[str, list[str]] = {}
        for it in items:
            self.by_kind.setdefault(it.kind, []).append(it.name)
        self.aliases = catalog.aliases()
        self.table = _phrase_table()
        self.used_as_subject: set[str] = set()
        self.history: list[str] = []
        self.last_reference: str | None = None

    def tokens(self, words: list[str]) -> list[_Tok]:
        out: list[_Tok] = []
        i = 0
        while i < len(words):
            hit = self._object_at(words, i) or self._phrase_at(words, i)
            if hit is not None:
                out.append(replace(hit[0], pos=i, end=i + hit[1]))
                i += hit[1]
                continue
            kind = _WORD_KINDS.get(words[i])
            if kind is not None:
                out.append(_Tok(kind, pos=i, end=i + 1))
            i += 1
        return out

    def _object_at(self, words: list[str], i: int) -> tuple[_Tok, int] | None:
        for n in range(min(_MAX_OBJECT_WORDS, len(words) - i), 0, -1):
            text = " ".join(words[i:i + n])
            if text in self.instances and text not in self.by_kind:
                return _Tok("obj", text), n
            spec = self.catalog.lookup(text)
            if spec is not None:
                plural = normalize_name(text) not in self.aliases
                kind = "obj" if spec.name in self.by_kind else "foreign"
                return _Tok(kind, spec.name, plural), n
        return None

    def _phrase_at(self, words: list[str], i: int) -> tuple[_Tok, int] | None:
        if words[i] in self.table.fillers:
            return None
        kept: list[int] = []
        j = i
        while j < len(words) and len(kept) < self.table.longest:
            if words[j] not in self.table.fillers:
                kept.append(j)
            j += 1
        for n in range(len(kept), 0, -1):
            hit = self.table.phrases.get(tuple(words[k] for k in kept[:n]))
            if hit is not None:
                return _Tok("rel", hit[0], bare=hit[1]), kept[n - 1] - i + 1
        return None

    def subjects(self, tok: _Tok) -> list[str]:
        if tok.value not in self.by_kind:
            return [tok.value]
        free = [n for n in self.by_kind[tok.value] if n not in self.used_as_subject]
        if not free:
            return [self.by_kind[tok.value][0]]
        return free if tok.plural else free[:1]

    def reference(self, tok: _Tok, subjects: Sequence[str]) -> str | None:
        if tok.kind == "pron":
            if self.last_reference is not None and self.last_reference not in subjects:
                return self.last_reference
            return next((n for n in reversed(self.history) if n not in subjects), None)
        names = self.by_kind.get(tok.value, [tok.value])
        return next((n for n in names if n not in subjects), names[0])


def _combine(rels: Sequence[str]) -> str:
    """One relation from the phrases before a reference: the directional ones win, and a
    vertical plus a horizontal one make a diagonal."""
    directional = [r for r in rels if r in DIRECTION and r not in STACKING]
    if not directional:
        stacking = [r for r in rels if r in STACKING]
        return stacking[-1] if stacking else CENTER
    dx = next((DIRECTION[r][0] for r in reversed(directional) if DIRECTION[r][0]), 0)
    dy = next((DIRECTION[r][1] for r in reversed(directional) if DIRECTION[r][1]), 0)
    if any(DIRECTION[r][0] and DIRECTION[r][1] for r in directional):
        return next(r for r in reversed(directional) if DIRECTION[r][0] and DIRECTION[r][1])
    return next(r for r, d in DIRECTION.items() if d == (dx, dy) and r not in STACKING)


@dataclass
class _LineResult:
    relations: list[Relation]
    dropped: bool = False
    last_reference: str | None = None
    last_subjects: list[str] = field(default_factory=list)


_THINGS = ("obj", "foreign")


def _read_sentence(toks: list[_Tok], reader: _Reader, line: str, out: _LineResult) -> None:
    """Adds the relations of one sentence's tokens to ``out``."""

    def emit(subject_toks: Sequence[_Tok], rel: str, ref_tok: _Tok | None, negated: bool,
             names: Sequence[str] = ()) -> None:
        if negated or any(t.kind == "foreign" for t in subject_toks) or (
                ref_tok is not None and ref_tok.kind == "foreign"):
            out.dropped = True
            return
        subjects = list(names) or [s for t in subject_toks for s in reader.subjects(t)]
        reference = None if ref_tok is None else reader.reference(ref_tok, subjects)
        if not subjects or (ref_tok is not None and reference is None):
            out.dropped = True
            return
        for subject in subjects:
            if subject == reference:
                out.dropped = True
                continue
            out.relations.append(Relation(subject, rel, reference, line))
            reader.used_as_subject.add(subject)
            reader.history.append(subject)
        out.last_subjects = subjects
        if reference is not None:
            reader.history.append(reference)
            reader.last_reference = out.last_reference = reference

    start = i = _read_fronted(toks, emit)
    chained = -1  # index of the last reference, which may open the next clause
    while i < len(toks):
        if toks[i].kind not in _THINGS:
            i += 1
            continue
        follow = i == chained and i + 1 < len(toks) and (
            toks[i + 1].pos - toks[i].end <= _MAX_FOLLOW_GAP)
        group = [i] if follow else _group(toks, i)
        j = group[-1] + 1
        which = False
        if follow and j + 1 < len(toks) and toks[j].kind in ("and", "which") and (
                toks[j + 1].kind == "rel"):
            which = toks[j].kind == "which"
            j += 1
        rels: list[_Tok] = []
        while j < len(toks) and toks[j].kind == "rel":
            rels.append(toks[j])
            j += 1
        if not rels:
            i += 1
            continue
        rel = _combine([t.value for t in rels])
        negated = any(t.kind == "neg" for t in toks[start:j])
        target = (toks[j] if not rels[-1].bare and j < len(toks)
                  and toks[j].kind in (*_THINGS, "pron") else None)
        subjects = [toks[g] for g in group]
        # After "S <rel> R", a further phrase is about S again ("..., above the knife"),
        # unless "which"/"that" makes R its subject.
        same = out.last_subjects if follow and not which else ()
        next_i = j
        if rel == CENTER:
            emit(subjects, CENTER, None, negated)
        elif target is not None and target.kind != "pron":
            emit(subjects, rel, target, negated, same)
            chained = next_i = j
        elif rel in STACKING and target is None:
            pass  # a stray "in"/"on" ("as is customary in Western settings")
        elif same:
            emit([], rel, toks[i], negated, same)  # "left of the fork, slightly above (it)"
            next_i = j + (target is not None)
        elif target is not None:
            if any(t.kind == "with" for t in toks[start:i]):
                out.dropped = True  # "..., with the bread on it": "it" is ambiguous
            else:
                emit(subjects, rel, target, negated)
            next_i = j + 1
        elif out.last_reference is not None:
            emit(subjects, rel, _Tok("obj", out.last_reference), negated)
        elif (ahead := _reference_ahead(toks, j)) is not None:
            emit(subjects, rel, toks[ahead], negated)
        else:
            out.dropped = True
        i = start = next_i


def _read_fronted(toks: list[_Tok], emit: Callable[..., None]) -> int:
    """Reads "To the left of the plate, place the fork." / "In the center, place the plate."
    at the start of a sentence; returns the index of the first token left unread."""
    k = 0
    while k < len(toks) and toks[k].kind == "neg":
        k += 1
    rels: list[str] = []
    while k < len(toks) and toks[k].kind == "rel":
        rels.append(toks[k].value)
        k += 1
    if not rels:
        return 0
    rel = _combine(rels)
    ref = (toks[k] if rel != CENTER and not toks[k - 1].bare and k < len(toks)
           and toks[k].kind in (*_THINGS, "pron") else None)
    s0 = k + 1 if ref is not None else k
    group = _group(toks, s0)
    after = group[-1] + 1 if group else s0
    if not group or (rel != CENTER and ref is None) or (
            after < len(toks) and toks[after].kind == "rel"):
        return 0
    emit([toks[g] for g in group], rel, ref, any(t.kind == "neg" for t in toks[:after]))
    return after


def _reference_ahead(toks: list[_Tok], j: int) -> int | None:
    """The reference of a later clause that an elided one shares: in "the fork on the left
    and the knife on the right of the plate", the plate."""
    m = j
    while m < len(toks) and toks[m].kind in ("and", "obj", "rel"):
        if toks[m].kind == "obj" and toks[m - 1].kind == "rel" and not toks[m - 1].bare:
            return m
        m += 1
    return None


def _group(toks: list[_Tok], i: int) -> list[int]:
    """Indices of "A and B and C" starting at ``i`` (empty when ``toks[i]`` is no object)."""
    if i >= len(toks) or toks[i].kind not in ("obj", "foreign"):
        return []
    group = [i]
    while (group[-1] + 2 < len(toks) and toks[group[-1] + 1].kind == "and"
           and toks[group[-1] + 2].kind in ("obj", "foreign")):
        group.append(group[-1] + 2)
    return group


def _merge_diagonals(rels: list[Relation]) -> list[Relation]:
    """One line's "left of R" and "above R" for the same subject, as "above and to the left
    of R" (as in "to the left of the fork, slightly above it")."""
    out: list[Relation] = []
    for rel in rels:
        twin = next((k for k, r in enumerate(out) if r.subject == rel.subject
                     and r.reference == rel.reference and r.relation != rel.relation
                     and _orthogonal(r.relation, rel.relation)), None)
        if twin is None:
            out.append(rel)
        else:
            out[twin] = Relation(rel.subject, _combine([out[twin].relation, rel.relation]),
                                 rel.reference, rel.line)
    return out


def _orthogonal(a: str, b: str) -> bool:
    da, db = DIRECTION.get(a), DIRECTION.get(b)
    return (da is not None and db is not None and 0 in da and 0 in db and da != (0, 0)
            and db != (0, 0) and (da[0] == 0) != (db[0] == 0))


def read_answer(text: str, items: Sequence[Item], catalog: Catalog
                ) -> tuple[list[Relation], list[str]]:
    """The relations ``text`` states between ``items``, and the lines it could not fully use
    (both as cleaned source lines; see the module docstring)."""
    reader = _Reader(items, catalog)
    relations: list[Relation] = []
    ignored: list[str] = []
    for raw in text.splitlines():
        source = _clean(raw)
        if not source:
            continue
        result = _LineResult([])
        mentions = False
        for sentence in _SENTENCES.split(source):
            toks = reader.tokens(_words(_clean(sentence)))
            mentions = mentions or any(t.kind in _THINGS for t in toks)
            _read_sentence(toks, reader, source, result)
        relations += _merge_diagonals(result.relations)
        if (result.dropped or (mentions and not result.relations)) and source not in ignored:
            ignored.append(source)
    return relations, ignored
