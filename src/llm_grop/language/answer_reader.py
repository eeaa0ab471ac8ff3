"""Reading spatial relations out of free text: an LLM's answers to Template 1 and its
follow-ups, and the user's preferences (:func:`parse_relations`).

How an answer is read:

* It works line by line, and within a line sentence by sentence. Numbering
  ("1.", "1)", "Step 2:"), bullets ("-", "*", "•"), markdown, articles and
  capitals are ignored. ``Relation.line`` and ``ParsedAnswer.ignored`` hold the
  source line stripped of surrounding space, numbering, bullets and markdown
  ("2. **Place the fork** left of the plate." -> "Place the fork left of the plate.").
* Objects are found through the catalog (names, synonyms, plurals: "fork" is
  the dinner fork, "teacup" the mug, "coaster" the mug mat), longest first.
  Catalog objects that were not requested are *unrequested*.
* Relation phrases come from the one vocabulary, ``language/vocabulary.yaml``
  (paraphrases such as "on the left-hand side of", "behind", "in front of", "in" for "on
  top of"). Its ambiguous words become choices: "S beside R" (left or right) and "S1 and
  S2 either side of R" (:attr:`ParsedAnswer.choices`).
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
  naming no object ("Sure! Here is a typical arrangement:") are not. An ignored
  line is cut to :data:`MAX_IGNORED_CHARS` characters ("…" ends a cut one), and
  past :data:`MAX_IGNORED_LINES` different ones a last entry says how many more
  there were ("… and 57 more lines"), so that a huge answer is never echoed whole.
* Instances: when items share a kind ("dinner fork", "dinner fork 2"), a
  mention of the kind as a subject is the first instance not yet used as a
  subject in this answer (a plural mention, "the forks", is every such
  instance); as a reference it is the first instance that is not a subject of
  the same relation ("one fork to the left of the other fork"). "dinner fork
  2" is matched as written.

Cutting lines into sentences, words and tokens is :mod:`llm_grop.language.answer_tokens`;
this module reads relations out of the tokens. Both work in time linear in the answer's
length (a megabyte-long answer takes well under a second).
"""

from __future__ import annotations

import functools
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from llm_grop.language.answer_tokens import THINGS, Tok, Tokenizer, clean, sentences
from llm_grop.language.vocabulary import BESIDE, EITHER_SIDE, beside, either_side
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import CENTER, DIRECTION, STACKING, Choice, Relation

#: Most words between a reference and a phrase that continues its clause
#: ("the plate, slightly above ..."), so far-off prose does not.
_MAX_FOLLOW_GAP = 3
#: Most characters of an ignored line that are kept (a longer one ends in "…"), so a
#: huge answer is never echoed whole in warnings.
MAX_IGNORED_CHARS = 120
#: Most ignored lines kept per answer; one more entry then says how many were left out.
MAX_IGNORED_LINES = 20


class _Reader:
    """Keeps the state of one answer: the subjects used and the objects named so far."""

    def __init__(self, items: Sequence[Item], catalog: Catalog) -> None:
        self.tokenizer = Tokenizer(items, catalog)
        self.by_kind: dict[str, list[str]] = {}
        for it in items:
            self.by_kind.setdefault(it.kind, []).append(it.name)
        self.used_as_subject: set[str] = set()
        # Objects related so far, the most recent last (a name moves to the end when it
        # comes again): only the latest mention of each matters to "it".
        self.recent: dict[str, None] = {}
        self.last_reference: str | None = None

    def mention(self, name: str) -> None:
        """Notes that ``name`` was just related."""
        self.recent.pop(name, None)
        self.recent[name] = None

    def subjects(self, tok: Tok) -> list[str]:
        if tok.value not in self.by_kind:
            return [tok.value]
        free = [n for n in self.by_kind[tok.value] if n not in self.used_as_subject]
        if not free:
            return [self.by_kind[tok.value][0]]
        return free if tok.plural else free[:1]

    def reference(self, tok: Tok, subjects: Sequence[str]) -> str | None:
        if tok.kind == "pron":
            if self.last_reference is not None and self.last_reference not in subjects:
                return self.last_reference
            return next((n for n in reversed(self.recent) if n not in subjects), None)
        names = self.by_kind.get(tok.value, [tok.value])
        return next((n for n in names if n not in subjects), names[0])


@functools.lru_cache(maxsize=1024)
def _combine(rels: tuple[str, ...]) -> str:
    """One relation from the phrases before a reference: the directional ones win, and a
    vertical plus a horizontal one make a diagonal."""
    directional = [r for r in rels if r in DIRECTION and r not in STACKING]
    if not directional:
        stacking = [r for r in rels if r in STACKING]
        ambiguous = [r for r in rels if r in (BESIDE, EITHER_SIDE)]
        return stacking[-1] if stacking else ambiguous[-1] if ambiguous else CENTER
    dx = next((DIRECTION[r][0] for r in reversed(directional) if DIRECTION[r][0]), 0)
    dy = next((DIRECTION[r][1] for r in reversed(directional) if DIRECTION[r][1]), 0)
    if any(DIRECTION[r][0] and DIRECTION[r][1] for r in directional):
        return next(r for r in reversed(directional) if DIRECTION[r][0] and DIRECTION[r][1])
    return next(r for r, d in DIRECTION.items() if d == (dx, dy) and r not in STACKING)


@dataclass
class _LineResult:
    relations: list[Relation]
    choices: list[Choice] = field(default_factory=list)
    dropped: bool = False
    last_reference: str | None = None
    last_subjects: list[str] = field(default_factory=list)


def _read_sentence(toks: list[Tok], reader: _Reader, line: str, out: _LineResult) -> None:
    """Adds the relations of one sentence's tokens to ``out``."""

    def emit(subject_toks: Sequence[Tok], rel: str, ref_tok: Tok | None, negated: bool,
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
        if rel in (BESIDE, EITHER_SIDE) and (reference is None or reference in subjects or (
                rel == EITHER_SIDE and len(subjects) != 2)):
            out.dropped = True
            return
        if rel == EITHER_SIDE:
            out.choices.append(either_side(subjects[0], subjects[1], reference, _kept(line)))
        for subject in subjects:
            if subject == reference:
                out.dropped = True
                continue
            if rel == BESIDE:
                out.choices.append(beside(subject, reference, _kept(line)))
            elif rel != EITHER_SIDE:
                out.relations.append(Relation(subject, rel, reference, _kept(line)))
            reader.used_as_subject.add(subject)
            reader.mention(subject)
        out.last_subjects = subjects
        if reference is not None:
            reader.mention(reference)
            reader.last_reference = out.last_reference = reference

    start = i = _read_fronted(toks, emit)
    chained = -1  # index of the last reference, which may open the next clause
    ahead: list[int | None] | None = None  # _references_ahead(toks), once it is needed
    while i < len(toks):
        if toks[i].kind not in THINGS:
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
        rels: list[Tok] = []
        while j < len(toks) and toks[j].kind == "rel":
            rels.append(toks[j])
            j += 1
        if not rels:
            # The rest of the group ends at the same j, so has no phrase either; skipping
            # it keeps "A and B and C and ..." linear.
            i = i + 1 if follow else j
            continue
        rel = _combine(tuple(t.value for t in rels))
        negated = any(t.kind == "neg" for t in toks[start:j])
        target = (toks[j] if not rels[-1].bare and j < len(toks)
                  and toks[j].kind in (*THINGS, "pron") else None)
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
            emit(subjects, rel, Tok("obj", out.last_reference), negated)
        else:
            ahead = ahead or _references_ahead(toks)
            shared = ahead[j]
            if shared is not None:
                emit(subjects, rel, toks[shared], negated)
            else:
                out.dropped = True
        i = start = next_i


def _read_fronted(toks: list[Tok], emit: Callable[..., None]) -> int:
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
    rel = _combine(tuple(rels))
    ref = (toks[k] if rel != CENTER and not toks[k - 1].bare and k < len(toks)
           and toks[k].kind in (*THINGS, "pron") else None)
    s0 = k + 1 if ref is not None else k
    group = _group(toks, s0)
    after = group[-1] + 1 if group else s0
    if not group or (rel != CENTER and ref is None) or (
            after < len(toks) and toks[after].kind == "rel"):
        return 0
    emit([toks[g] for g in group], rel, ref, any(t.kind == "neg" for t in toks[:after]))
    return after


def _references_ahead(toks: list[Tok]) -> list[int | None]:
    """For each index ``j``, the reference of a later clause that an elided one ending at
    ``j`` shares (in "the fork on the left and the knife on the right of the plate", the
    plate): the first object from ``j`` on, within a run of "and"s, objects and phrases,
    that follows a phrase taking a reference. One backward pass, so that reading every
    clause of a long sentence stays linear."""
    out: list[int | None] = [None] * (len(toks) + 1)
    for m in range(len(toks) - 1, 0, -1):
        if toks[m].kind in ("and", "obj", "rel"):
            is_ref = (toks[m].kind == "obj" and toks[m - 1].kind == "rel"
                      and not toks[m - 1].bare)
            out[m] = m if is_ref else out[m + 1]
    return out


def _group(toks: list[Tok], i: int) -> list[int]:
    """Indices of "A and B and C" starting at ``i`` (empty when ``toks[i]`` is no object)."""
    if i >= len(toks) or toks[i].kind not in ("obj", "foreign"):
        return []
    group = [i]
    while (group[-1] + 2 < len(toks) and toks[group[-1] + 1].kind == "and"
           and toks[group[-1] + 2].kind in ("obj", "foreign")):
        group.append(group[-1] + 2)
    return group


#: The relations along one axis, and the relations across it.
_HORIZONTAL = tuple(r for r, (dx, dy) in DIRECTION.items() if dx and not dy)
_VERTICAL = tuple(r for r, (dx, dy) in DIRECTION.items() if dy and not dx)
_ACROSS = {**dict.fromkeys(_HORIZONTAL, _VERTICAL), **dict.fromkeys(_VERTICAL, _HORIZONTAL)}


def _merge_diagonals(rels: list[Relation]) -> list[Relation]:
    """One line's "left of R" and "above R" for the same subject, as "above and to the left
    of R" (as in "to the left of the fork, slightly above it").

    A relation merges with the first earlier one across its axis between the same
    objects. Those are kept in queues by (subject, reference, relation), so that a line of
    thousands of relations is merged in linear time.
    """
    out: list[Relation] = []
    waiting: dict[tuple[str, str | None, str], deque[int]] = {}
    for rel in rels:
        across = _ACROSS.get(rel.relation, ())
        queues = [q for r in across if (q := waiting.get((rel.subject, rel.reference, r)))]
        if not queues:
            if across:
                waiting.setdefault((rel.subject, rel.reference, rel.relation),
                                   deque()).append(len(out))
            out.append(rel)
            continue
        # A merged relation is a diagonal, which merges with nothing more.
        twin = min(queues, key=lambda q: q[0]).popleft()
        out[twin] = Relation(rel.subject, _combine((out[twin].relation, rel.relation)),
                             rel.reference, rel.line)
    return out


#: Longest source line a relation keeps, in characters: it is quoted in warnings and in
#: the JSON's ``conflicts``, and a relation is one short sentence.
MAX_LINE_CHARS = 500


def _kept(line: str) -> str:
    """``line`` as a relation keeps it: at most :data:`MAX_LINE_CHARS` characters."""
    return line if len(line) <= MAX_LINE_CHARS else line[:MAX_LINE_CHARS - 1] + "…"


def _shorten(line: str) -> str:
    """``line`` cut to :data:`MAX_IGNORED_CHARS` characters, ending in "…" when cut."""
    if len(line) <= MAX_IGNORED_CHARS:
        return line
    return line[:MAX_IGNORED_CHARS - 1].rstrip() + "…"


@dataclass(frozen=True)
class ParsedAnswer:
    """What an answer says: its relations in line order, the ambiguous ones ("the knife
    beside the plate") as choices, the requested item names neither mentions, and the
    source lines it could not fully use."""

    relations: tuple[Relation, ...]
    missing: tuple[str, ...]
    ignored: tuple[str, ...]
    choices: tuple[Choice, ...] = ()


def parse_relations(text: str, items: Sequence[Item], catalog: Catalog) -> ParsedAnswer:
    """The relations ``text`` (an LLM's answer, a preference) states between the requested
    ``items``, in line order, with the item names no relation mentions and the lines that
    could not be fully used (see the module docstring).

    Ignored lines are shortened to :data:`MAX_IGNORED_CHARS` characters and, past the
    first :data:`MAX_IGNORED_LINES` different ones, counted in a last entry
    "… and N more lines".
    """
    reader = _Reader(items, catalog)
    relations: list[Relation] = []
    choices: list[Choice] = []
    ignored: list[str] = []
    seen: set[str] = set()
    for raw in text.splitlines():
        source = clean(raw)
        if not source:
            continue
        result = _LineResult([])
        mentions = False
        for sentence in sentences(source):
            toks = reader.tokenizer.sentence_tokens(sentence)
            mentions = mentions or any(t.kind in THINGS for t in toks)
            _read_sentence(toks, reader, source, result)
        relations += _merge_diagonals(result.relations)
        choices += result.choices
        short = _shorten(source)
        if (result.dropped or (mentions and not result.relations and not result.choices)) \
                and short not in seen:
            seen.add(short)
            if len(ignored) < MAX_IGNORED_LINES:
                ignored.append(short)
    if len(seen) > len(ignored):
        ignored.append(f"… and {len(seen) - len(ignored)} more lines")
    mentioned = {r.subject for r in relations} | {r.reference for r in relations} | {
        r.subject for c in choices for o in c.options for r in o} | {
        r.reference for c in choices for o in c.options for r in o}
    missing = tuple(it.name for it in items if it.name not in mentioned)
    return ParsedAnswer(tuple(relations), missing, tuple(ignored), tuple(choices))
