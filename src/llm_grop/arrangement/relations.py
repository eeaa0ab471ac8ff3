"""Template 1, its grammar, follow-up prompts, and the parser of LLM answers (paper §III-A).

The parser reads relations out of real LLM text: numbering, bullets, markdown,
articles, plurals and synonyms (through the catalog), several relations on one
line, prose around them, and the paraphrases listed in
``prompts/relation_phrases.yaml``. It never invents a relation.

When two items share a kind ("dinner fork", "dinner fork 2"), a mention of the
kind as a subject is the first instance not yet used as a subject in that
answer; as a reference it is the first instance. Instance names ("dinner fork 2")
are matched as they are.
"""

from __future__ import annotations

import functools
import json
import re
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources

import yaml

from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import CENTER, RELATION_NAMES, Relation

#: Template 1's [spatial relationships] slot, in the authors' wording.
SPATIAL_RELATIONSHIPS = ", ".join(RELATION_NAMES[:-1]) + ", and center"

_ARTICLES = {"the", "a", "an"}
_MAX_OBJECT_WORDS = 5


@dataclass(frozen=True)
class ParsedAnswer:
    """What an answer says: relations in line order, requested items it left out,
    and the lines it could not use (they name unrequested objects or hold no relation)."""

    relations: tuple[Relation, ...]
    missing: tuple[str, ...]
    ignored: tuple[str, ...]


@functools.lru_cache(maxsize=8)
def _asset(name: str) -> str:
    return resources.files("llm_grop.arrangement").joinpath(f"prompts/{name}").read_text("utf-8")


@functools.lru_cache(maxsize=1)
def _phrases() -> dict[tuple[str, ...], str]:
    """Phrase (as words) -> contract relation name."""
    table = yaml.safe_load(_asset("relation_phrases.yaml"))
    out: dict[tuple[str, ...], str] = {}
    for relation, phrases in table.items():
        for phrase in phrases:
            out[tuple(str(phrase).split())] = relation
    return out


def _with_article(name: str) -> str:
    return f"{'an' if name[0] in 'aeiou' else 'a'} {name}"


def _object_list(names: Sequence[str]) -> str:
    named = [_with_article(n) for n in names]
    if len(named) <= 2:
        return " and ".join(named)
    return ", ".join(named[:-1]) + ", and " + named[-1]


def template1_prompt(items: Sequence[Item], *, examples: str | None = None, notes: str = ""
                     ) -> str:
    """Template 1 with its slots filled: relationships, examples, objects, notes.

    ``examples=None`` uses the paper's few-shot examples; ``""`` asks zero-shot.
    """
    block = _asset("template1_examples.txt") if examples is None else examples
    return _asset("template1.txt").format(
        spatial_relationships=SPATIAL_RELATIONSHIPS,
        examples=f"{block.strip(chr(10))}\n" if block.strip() else "",
        objects=_object_list([it.name for it in items]),
        notes=f" {notes.strip()}" if notes.strip() else "").strip()


def followup_prompt(missing: str, anchor: str) -> str:
    """The authors' follow-up for an object the answer left out."""
    return _asset("followup.txt").format(missing=missing, anchor=anchor,
                                         spatial_relationships=SPATIAL_RELATIONSHIPS).strip()


def _lit(text: str) -> str:
    return json.dumps(text)


def _line_rule(pairs: Sequence[tuple[str, str]], centres: Sequence[str]) -> str:
    rel = " | ".join(_lit(r) for r in RELATION_NAMES if r != CENTER)
    alts = [f"{_lit(s + ' ')} rel {_lit(' the ' + o)}" for s, o in pairs]
    alts += [_lit(f"{c} in the center of the table") for c in centres]
    return (f'line ::= "Place the " ( {" | ".join(alts)} ) "."\n'
            f"rel ::= {rel}\n")


def template1_grammar(items: Sequence[Item]) -> str:
    """GBNF: 1 to n lines "Place the S <relation> the O." (S != O) or "... in the center".

    One line per object, as the template asks; a longer answer from a weak
    model only repeats itself and costs time.
    """
    names = [it.name for it in items]
    pairs = [(s, o) for s in names for o in names if s != o]
    extra = max(len(names) - 1, 1)
    return f'root ::= line ("\\n" line){{0,{extra}}}\n' + _line_rule(pairs, names)


def followup_grammar(missing: str, anchor: str) -> str:
    """GBNF: one line relating ``missing`` and ``anchor``, either as the subject."""
    return "root ::= line\n" + _line_rule([(missing, anchor), (anchor, missing)], [])


def _clean(line: str) -> str:
    line = re.sub(r"\s+", " ", re.sub(r"[*_`#>]", " ", line))
    line = re.sub(r"^\s*(?:step\s*\d+\s*[:.)-]?|\(?\d+[.):]|[-•+])\s*", "", line, flags=re.I)
    return line.strip()


def _words(line: str) -> list[str]:
    text = re.sub(r"[^a-z0-9' ]+", " ", line.lower().replace("-", " "))
    return [w for w in text.split() if w not in _ARTICLES]


class _Reader:
    """Finds object mentions and relation phrases in one answer."""

    def __init__(self, items: Sequence[Item], catalog: Catalog) -> None:
        self.catalog = catalog
        self.instances = {it.name: it for it in items}
        self.by_kind: dict[str, list[str]] = {}
        for it in items:
            self.by_kind.setdefault(it.kind, []).append(it.name)
        self.used_as_subject: set[str] = set()
        self.phrases = _phrases()
        self.max_phrase = max(len(p) for p in self.phrases)

    def tokens(self, words: list[str]) -> list[tuple[str, str]]:
        """``("obj", kind-or-instance)``, ``("unknown-obj", kind)`` and ``("rel", name)``."""
        out: list[tuple[str, str]] = []
        i = 0
        while i < len(words):
            hit = self._object_at(words, i) or self._phrase_at(words, i)
            if hit is None:
                i += 1
                continue
            token, length = hit
            out.append(token)
            i += length
        return out

    def _object_at(self, words: list[str], i: int) -> tuple[tuple[str, str], int] | None:
        for n in range(min(_MAX_OBJECT_WORDS, len(words) - i), 0, -1):
            text = " ".join(words[i:i + n])
            if text in self.instances and text not in self.by_kind:
                return ("obj", text), n
            spec = self.catalog.lookup(text)
            if spec is not None:
                kind = "obj" if spec.name in self.by_kind else "unknown-obj"
                return (kind, spec.name), n
        return None

    def _phrase_at(self, words: list[str], i: int) -> tuple[tuple[str, str], int] | None:
        for n in range(min(self.max_phrase, len(words) - i), 0, -1):
            rel = self.phrases.get(tuple(words[i:i + n]))
            if rel is not None:
                return ("rel", rel), n
        return None

    def instance(self, mention: str, as_subject: bool) -> str:
        if mention not in self.by_kind:
            return mention
        names = self.by_kind[mention]
        if as_subject:
            for name in names:
                if name not in self.used_as_subject:
                    return name
        return names[0]


def _relations_in(line: str, reader: _Reader) -> tuple[list[Relation], bool]:
    """Relations in one line, and whether the line named an unrequested object."""
    tokens = reader.tokens(_words(line))
    found: list[Relation] = []
    foreign = any(kind == "unknown-obj" for kind, _ in tokens)
    i = 0
    while i < len(tokens):
        kind, value = tokens[i]
        if kind not in ("obj", "unknown-obj"):
            i += 1
            continue
        j = i + 1
        rels: list[str] = []
        while j < len(tokens) and tokens[j][0] == "rel":
            rels.append(tokens[j][1])
            j += 1
        if not rels:
            i += 1
            continue
        target = tokens[j] if j < len(tokens) else None
        non_centre = [r for r in rels if r != CENTER]
        if target is not None and target[0] != "rel" and non_centre:
            rel = max(non_centre, key=len)
            if kind == "obj" and target[0] == "obj":
                subject = reader.instance(value, as_subject=True)
                reference = reader.instance(target[1], as_subject=False)
                if subject != reference:
                    found.append(Relation(subject, rel, reference, line))
                    reader.used_as_subject.add(subject)
            i = j
        elif CENTER in rels and kind == "obj":
            subject = reader.instance(value, as_subject=True)
            found.append(Relation(subject, CENTER, None, line))
            reader.used_as_subject.add(subject)
            i = j
        else:
            i = j
    return found, foreign


def parse_relations(text: str, items: Sequence[Item], catalog: Catalog) -> ParsedAnswer:
    """Relations an LLM answer states between the requested ``items``."""
    reader = _Reader(items, catalog)
    relations: list[Relation] = []
    ignored: list[str] = []
    for raw in re.split(r"\n|(?<=[.!?])\s+(?=(?:place|put|set|the|then)\b)", text, flags=re.I):
        line = _clean(raw)
        if not line:
            continue
        found, foreign = _relations_in(line, reader)
        relations += found
        if foreign or (not found and any(k == "obj" for k, _ in reader.tokens(_words(line)))):
            ignored.append(line)
    mentioned = {r.subject for r in relations} | {r.reference for r in relations}
    missing = tuple(it.name for it in items if it.name not in mentioned)
    return ParsedAnswer(tuple(relations), missing, tuple(ignored))
