"""Template 1, its grammar and follow-up prompts (paper §III-A).

The prompts are the authors' wording, kept in ``prompts/*.txt``; the grammars
(GBNF, for llama.cpp backends) only constrain the *form* of an answer to the
template's "Place the X <relation> the Y." lines over the requested objects. The answers,
real and free LLM text (numbering, markdown, synonyms, paraphrases, several relations per
line), are read by :func:`llm_grop.language.answer_reader.parse_relations`.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from importlib import resources

from llm_grop.world.arrangement import Item
from llm_grop.world.relation import CENTER, RELATION_NAMES

#: Template 1's [spatial relationships] slot, in the authors' wording.
SPATIAL_RELATIONSHIPS = ", ".join(RELATION_NAMES[:-1]) + ", and " + RELATION_NAMES[-1]
#: The options a follow-up may use: every relation between two objects.
PAIR_RELATIONSHIPS = ", ".join(RELATION_NAMES[:-2]) + ", and " + RELATION_NAMES[-2]


@functools.lru_cache(maxsize=8)
def asset(name: str) -> str:
    """The text of ``prompts/NAME``, a template beside this module."""
    return resources.files("llm_grop.arrangement").joinpath(f"prompts/{name}").read_text("utf-8")


def with_article(name: str) -> str:
    """``name`` with its indefinite article: "an apple", "a plate"."""
    return f"{'an' if name[:1] in ('a', 'e', 'i', 'o', 'u') else 'a'} {name}"


def object_list(names: Sequence[str]) -> str:
    """``names`` as Template 1 lists them: "a plate, a fork, and a knife"."""
    named = [with_article(n) for n in names]
    if len(named) <= 2:
        return " and ".join(named)
    return ", ".join(named[:-1]) + ", and " + named[-1]


def template1_prompt(items: Sequence[Item], *, examples: str | None = None, notes: str = ""
                     ) -> str:
    """Template 1 with its slots filled: [spatial relationships], [examples], [objects], [notes].

    ``examples=None`` uses the paper's few-shot examples
    (``prompts/template1_examples.txt``); ``""`` asks zero-shot; any other text
    replaces them. ``notes`` is appended after the template's own note.
    """
    block = asset("template1_examples.txt") if examples is None else examples
    return asset("template1.txt").format(
        spatial_relationships=SPATIAL_RELATIONSHIPS,
        examples=f"\n{block.strip()}\n\n" if block.strip() else "",
        objects=object_list([it.name for it in items]),
        notes=f" {notes.strip()}" if notes.strip() else "").strip()


def followup_prompt(missing: str, anchor: str) -> str:
    """The authors' question for an object an answer left out, asking for one Place line."""
    return asset("followup.txt").format(a_missing=with_article(missing),
                                        a_anchor=with_article(anchor),
                                        spatial_relationships=PAIR_RELATIONSHIPS).strip()


def gbnf_literal(text: str) -> str:
    """``text`` as a double-quoted GBNF string literal."""
    out = []
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\x{ord(ch):02X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _grammar(root: str, pairs: Sequence[tuple[str, str]], centres: Sequence[str]) -> str:
    alts = [f"{gbnf_literal(s + ' ')} rel {gbnf_literal(' the ' + o)}" for s, o in pairs]
    alts += [gbnf_literal(f"{c} in the center of the table") for c in centres]
    rel = " | ".join(gbnf_literal(r) for r in RELATION_NAMES if r != CENTER)
    return (f"root ::= {root}\n"
            f'line ::= "Place the " ( {" | ".join(alts)} ) "."\n'
            f"rel ::= {rel}\n")


def template1_grammar(items: Sequence[Item]) -> str:
    """GBNF: 1 to 2n lines "Place the S <relation> the R." (S != R) or
    "Place the S in the center of the table.", over the requested item names.

    Lines are separated by a newline, and the answer may end after any line.
    """
    names = [it.name for it in items]
    if not names:
        raise ValueError("Template 1 needs at least one item")
    pairs = [(s, o) for s in names for o in names if s != o]
    more = max(2 * len(names) - 1, 0)
    return _grammar(f'line ("\\n" line){{0,{more}}}', pairs, names)


def followup_grammar(missing: str, anchor: str) -> str:
    """GBNF: one line relating ``missing`` and ``anchor``, either one as the subject."""
    return _grammar("line", [(missing, anchor), (anchor, missing)], [])
