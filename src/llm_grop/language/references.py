"""What "it" and a phrase without a reference ("on the left") refer to in a request read by
the catalog matcher: one object, or none when the request leaves it open (then the LLM
reads the request)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from llm_grop.language.parts import Mention

if TYPE_CHECKING:
    from llm_grop.language.matcher import MatchReader


def antecedent(reader: MatchReader, before: int, exclude: set[int],
               subject: int | None = None) -> int | None:
    """The one object "it" may stand for at token ``before`` (said of part ``subject``), or
    ``None`` when the request leaves it open.

    Of the objects written before it and not in ``exclude``, those of the nearest sentence
    that has any count: the only one, else the object a "with" introduced the subject by,
    when that object is in no relation yet ("a bread plate with bread on it"); any other
    choice ("a bowl on a plate with a spoon next to it") is left to the LLM.
    """
    by_sentence: dict[int, list[int]] = {}
    for k, p in enumerate(reader.parts):
        if isinstance(p, Mention) and p.end <= before and k not in exclude:
            by_sentence.setdefault(reader.sentence_at(p.start), []).append(k)
    if not by_sentence:
        return None
    group = by_sentence[max(by_sentence)]
    if len(group) == 1:
        return group[0]
    separator, previous = reader.joined.get(subject, ((), None)) if subject is not None \
        else ((), None)
    related = {k.subject for k in reader.links} | {k.reference for k in reader.links
                                                   if k.reference is not None}
    if separator == ("with",) and previous in group and previous not in related:
        return previous
    return None


def resolve_references(reader: MatchReader) -> None:
    """Gives each pronoun and bare link its reference, or records a doubt.

    "it" is its :func:`antecedent`; objects placed by "it" or a bare phrase are no
    antecedents. A bare phrase ("on the left") takes the reference of the next link of its
    sentence that names one, else of the last link before it that names one, else the
    antecedent of its subject.
    """
    links = reader.links
    placed = {k.subject for k in links if k.kind in ("pronoun", "bare")}
    for n, link in enumerate(links):
        if link.kind not in ("pronoun", "bare"):
            continue
        # Nor is what the subject is related to already: "a spoon on the napkin on the
        # right" says nothing of the napkin against the spoon.
        linked = {k.reference for k in links if k.subject == link.subject and k is not link} \
            | {k.subject for k in links if k.reference == link.subject}
        exclude = placed | linked | {link.subject} | (
            {link.partner} if link.partner is not None else set())
        ref: int | None = None
        if link.kind == "pronoun":
            ref = antecedent(reader, link.start, exclude, link.subject)
        else:
            sentence = reader.sentence_at(link.start)
            later = [k.reference for k in links[n + 1:] if k.kind == "named"
                     and reader.sentence_at(k.start) == sentence
                     and k.reference not in exclude]
            earlier = [k.reference for k in links[:n] if k.kind in ("named", "pronoun")
                       and k.reference is not None and k.reference not in exclude]
            ref = later[0] if later else earlier[-1] if earlier else \
                antecedent(reader, link.start, exclude, link.subject)
        if ref is None or ref == link.subject:
            reader.doubts.append(f"what {link.relation!r} refers to")
            continue
        link.reference = ref
