"""The words a request is read with, besides the catalog's names: counts, vague
quantities, fillers, separators, and the phrases that relate two objects.

:mod:`llm_grop.world.request` reads a request with these tables; they hold no catalog
knowledge, and no placement convention (a relation phrase only names the relation the
user said).
"""

from __future__ import annotations

from llm_grop.world.relation import ABOVE, BELOW, CENTER, LEFT, ON_TOP_OF, RIGHT, UNDER

NUMBERS: dict[str, int] = {
    "one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7,
    "eight": 8, "nine": 9, "ten": 10, "eleven": 11, "twelve": 12, "thirteen": 13,
    "fourteen": 14, "fifteen": 15, "sixteen": 16, "seventeen": 17, "eighteen": 18,
    "nineteen": 19, "twenty": 20, "thirty": 30,
}


def phrases(*texts: str) -> tuple[tuple[str, ...], ...]:
    """Each text as a tuple of its words."""
    return tuple(tuple(t.split()) for t in texts)


#: Phrases that count the next object. Articles also count 1, but may dangle harmlessly.
COUNT_PHRASES: dict[tuple[str, ...], int] = {
    **{(w,): n for w, n in NUMBERS.items()},
    ("a",): 1, ("an",): 1, ("another",): 1, ("single",): 1, ("a", "single"): 1,
    ("a", "couple", "of"): 2, ("couple", "of"): 2, ("a", "pair", "of"): 2, ("pair", "of"): 2,
    ("a", "dozen"): 12, ("dozen",): 12,
}
ARTICLES = phrases("a", "an", "one", "another")
#: Quantities that name no number: a plural after them still needs one.
VAGUE = phrases("some", "a few", "few", "several", "many", "a lot of", "lots of",
                "a bunch of", "more", "any", "extra", "a number of")
FILLERS = phrases(
    "for dinner", "for breakfast", "for lunch", "for supper", "for brunch", "for one",
    "for one person", "on the table", "at the table", "place setting", "thank you",
    "if you can", "if possible", "set up",
) + tuple((w,) for w in (
    "please", "kindly", "thanks", "thank", "you", "i", "i'd", "i'll", "i'm", "id", "we", "we'd",
    "let's", "would", "like", "love", "want", "wants", "need", "needs", "could", "can", "will",
    "may", "might", "must", "should", "shall", "me", "us", "set", "lay", "put", "place", "arrange",
    "get", "bring", "give", "serve", "prepare", "make", "setup", "up", "out", "down", "the",
    "table", "setting", "on", "onto", "at", "in", "into", "to", "for", "of", "its", "it", "it's",
    "their", "his", "her", "my", "our", "your", "this", "that", "these", "those", "there", "here",
    "is", "are", "be", "just", "only", "too", "as", "well", "now", "nicely", "neatly", "properly",
    "meal", "dinner", "breakfast", "lunch", "supper", "brunch", "have", "having", "eat", "today",
    "tonight", "ready", "going", "each", "apiece", "everyone", "everybody", "person",
))
SEPARATOR_WORDS = frozenset({"and", "with", "plus", "also", "then"})
SEPARATOR_CHARS = frozenset(",;:.!?&+/|()[]{}\n")

#: Phrases that relate the object before them to the object after them, as the user
#: said it ("a mug on a coaster": the mug on top of the mug mat).
RELATION_PHRASES: dict[tuple[str, ...], str] = {
    **dict.fromkeys(phrases("on", "onto", "on top of", "atop", "upon", "resting on",
                            "sitting on", "stacked on", "in", "inside", "into"), ON_TOP_OF),
    **dict.fromkeys(phrases("under", "underneath", "beneath"), UNDER),
    **dict.fromkeys(phrases("to the left of", "on the left of", "left of", "at the left of",
                            "on the left side of", "to the left side of"), LEFT),
    **dict.fromkeys(phrases("to the right of", "on the right of", "right of",
                            "at the right of", "on the right side of",
                            "to the right side of"), RIGHT),
    **dict.fromkeys(phrases("above", "behind", "beyond", "in back of"), ABOVE),
    **dict.fromkeys(phrases("below", "in front of"), BELOW),
}
#: Phrases that put the object before them at the table's centre.
CENTER_PHRASES: dict[tuple[str, ...], str] = dict.fromkeys(phrases(
    "in the center", "in the centre", "in the middle", "at the center", "at the centre",
    "in the center of the table", "in the centre of the table", "in the middle of the table",
    "at the center of the table", "at the centre of the table"), CENTER)
