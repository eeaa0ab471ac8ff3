"""What the fuzzers feed every text parser (shared by the Hypothesis tests in
``tests/fuzz`` and by ``benchmarks/fuzz.py``; ``fuzz_targets`` says how each parser is
called and what it must do).

Inputs come from :func:`random.Random`-driven generators, so the benchmark repeats a run
from its seed and the tests draw them through ``st.randoms()``:

* random Unicode (every category but surrogates; digits such as '²', '①', '１', '٣';
  separators, line breaks, controls), short or long;
* sentences built from the grammar of valid inputs (catalog names, synonyms and plurals,
  numbers and units, relation phrases, counts, numbering, markdown);
* valid inputs mutated (characters and words inserted, deleted, repeated, swapped);
* for the YAML and JSONL files, random structures dumped as YAML or JSON, the packaged
  files mutated, YAML oddities (anchors, tags, deep nesting) and bytes that are not UTF-8.
"""

from __future__ import annotations

import json
import math
import random
from collections.abc import Callable
from importlib import resources

import yaml

from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import RELATION_NAMES
from llm_grop.world.request import items_from_names

CATALOG = Catalog.load(use_env=False)
#: The requested items the answer and preference parsers read against (two forks, so that
#: instances are exercised).
ITEMS = items_from_names(["dinner plate", "dinner fork", "dinner fork", "dinner knife",
                          "water cup", "mug", "mug mat", "mug lid", "bread plate"], CATALOG)

Input = str | bytes

# ------------------------------------------------------------------ vocabulary

_NAMES = sorted({*CATALOG.aliases(), *(n + "s" for n in CATALOG.names()), "knives",
                 "strawberries", "loaves", "dinner fork 2", "dinner plate 2", "mug 3",
                 "spork", "blue mug", "salad forks", "teacups", "coasters"})
NUMBERS = ["0", "1", "2", "5", "7", "12", "30", "200", "201", "1000", "1,000", "1,5", "1e3",
           "2e-1", "1E2", "1e999", "9" * 40, "2.5", ".5", "5.", "0.05", "½", "2½", "¼", "⅓",
           "five", "twenty-two", "twenty five", "a", "an", "one and a half", "half an",
           "-5", "−5", "–5", "‐5", "－5", "minus 5", "１０", "²", "①", "٣", "𝟓", "NaN", "inf",
           "0x10", "1_000", "5-7", "5 to 7", "between 5 and 7", "5 or 6", "3/4"]
UNITS = ["cm", "cms", "centimeters", "centimetres", "mm", "millimeters", "m", "meters",
         "metre", "in", "in.", "inch", "inches", "″", "′′", "ft", "foot", "feet", "ｃｍ",
         "km", "yards", "cm²"]
_PHRASES = [*RELATION_NAMES, "left of", "right of", "behind", "in front of", "next to",
            "beside", "on the left", "on the right", "in the upper right", "to its left",
            "slightly to the left of", "directly above", "on", "in", "at the top of",
            "in the center of the table", "in the middle", "closer to the diner than",
            "above and slightly to the right of", "in a position to the right of"]
_GLUE = ["and", "or", "with", "plus", "&", "which", "that", "it", "its", "it's", "not",
         "never", "do not", "don't", "please", "place", "put", "the", "a", "an", "another",
         "some", "several", "a couple of", "a pair of", "a dozen", "two", "three", "twenty",
         "thirty", "for two", "for 4 people", "for 13", "three place settings",
         "set the table with",
         "I'd like", "'s", "from the diner's edge", "from the edge", "from the near edge",
         "about", "roughly", "away", "apart", "Sure!", "Here is", "Step 3:", "1.", "2)",
         "(a)", "b)", "A:", "answer:", "-", "*", "**", "#", "|", "•", ">", ",", ".", ";", ":",
         "!", "?", "(", ")", "[", "]", "/", "\n", "\n\n", "\t", "  ", "’", "`"]
#: Characters that have tripped text parsers: look-alike digits, dashes, spaces, line
#: breaks other than "\n", controls, case oddities.
SPECIAL_CHARS = ["²", "³", "¹", "₂", "①", "⑩", "１", "０", "٣", "߁", "𝟓", "½", "⅓", "Ⅻ",
                 "−", "–", "—", "‐", "‑", "－", "﹣", "\u00a0", "\u2009", "\u202f", "\u3000",
                 "\u200b", "\ufeff", "\u2028", "\u2029", "\x85", "\x0b", "\x0c", "\x1c",
                 "\r", "\r\n", "\x00", "\x7f", "İ", "ß", "ﬁ", "Σ", "ς", "\u0301", "″", "′",
                 "’", "“", "”", "…", "·", "¼", "﷽", "\U0001f374", "\U000e0041", "\U0010fffd"]
#: Counted objects ("two forks", "a pair of knives"), so that requests often read.
_COUNTED = [f"{count} {name}" for count in ("a", "an", "one", "two", "3", "12", "31",
                                            "a pair of", "a couple of", "a dozen", "another")
            for name in _NAMES]
#: Pieces of the LLM's reading of a request: its line format and its JSON.
_READING = ["diners:", "object:", "relation:", "|", " | ", '"a plate"', "with", "cm", "2 cm",
            "-3 cm", "center", "beside", "either side of", "table", "null", '{"diners": 2,',
            '"objects": [', '{"name": "fork", "count": 2, "words": "two forks"}', "]", "}",
            '"relations": [', '{"subject": "fork", "relation": "beside", "reference": "plate",'
            ' "distance_cm": null, "partner": null, "words": ""}', '"count": 13', '"count": 1.5',
            '"diners": true', '"distance_cm": -2', '"distance_cm": "2 inches"', "```json", "```"]
_WORDS_BY_KIND = {
    "request": [_COUNTED, _COUNTED, _COUNTED, _NAMES, NUMBERS[:30], _GLUE, _GLUE,
                _PHRASES, UNITS],
    "reading": [_READING, _READING, _NAMES, _PHRASES, NUMBERS, _GLUE],
    "answer": [_NAMES, _PHRASES, _GLUE, _GLUE],
    "distance": [NUMBERS, UNITS, _GLUE, _PHRASES],
    "preferences": [_NAMES, _PHRASES, NUMBERS, UNITS, _GLUE],
    "edge": [_NAMES, NUMBERS, UNITS, ["from the diner's edge", "from the edge", "from the",
                                      "edge", "near edge", "diner’s", "of the table"]],
}


def _valid_answers() -> list[str]:
    lines = ["Place the dinner plate in the center of the table.",
             "Place the dinner fork to the left of the dinner plate.",
             "2. **Place the knife** to the right of the plate.",
             "The mug on top of the coaster, and the lid on top of the mug.",
             "To the left of the plate, place the fork. The cup goes above it.",
             "- the fork on the left and the knife on the right of the plate",
             "Do not place the napkin under the bowl, which sits above the fork."]
    return ["\n".join(lines[:k]) for k in range(1, len(lines) + 1)]


VALID = {
    "request": ["set the table with a plate, two forks and a knife",
                "a dinner plate, a dinner fork and a dinner knife for two",
                "I'd like a mug on a coaster with its lid, please",
                "three place settings with a plate and a pair of forks",
                "a couple of strawberries & a fruit bowl plus bread",
                "a plate with a fork on its left and a knife beside it, 2 cm away",
                "the fork and the knife either side of the plate; a glass at the top right",
                "breakfast for two, and a mug of coffee on a coaster if you can"],
    "answer": _valid_answers(),
    "reading": ['diners: 2\nobject: 1 dinner plate | "a plate"\nobject: 2 fork\n'
                'relation: dinner fork | to the left of | dinner plate | 2 cm | "two forks left"\n'
                'relation: fork 2 | beside | plate\nrelation: plate | center',
                '{"diners": 1, "objects": [{"name": "mug", "count": 1, "words": "coffee"}, '
                '{"name": "mug mat", "count": 1, "words": "a coaster"}], "relations": '
                '[{"subject": "mug", "relation": "on top of", "reference": "mug mat", '
                '"distance_cm": null, "partner": null, "words": "a mug on a coaster"}]}',
                "object: 1 dinner fork\nobject: 1 dinner knife\nobject: 1 dinner plate\n"
                "relation: dinner fork | either side of | dinner plate | with dinner knife"],
    "distance": ["About 5-7 centimeters.", "2 inches", "Between 5 and 7 cm.", "1,000 mm",
                 "twenty-two centimeters to the left", "1. About 7", "2½ cm", "1e3 mm"],
    "preferences": ["the dinner fork to the left of the dinner plate",
                    "the dinner fork 2 cm to the left of the dinner plate\nmug lid on top of mug",
                    "the dinner plate 3 cm from the diner's edge",
                    "the knife right of the plate\nthe cup 5 cm from the edge\nthe fork left"],
    "edge": ["the dinner plate 3 cm from the diner's edge",
             "mug 10 cm from the near edge of the table\nthe forks 2 cm from the edge",
             "the plate −2 cm from the edge\nthe cup 1e3 mm from the diner’s edge",
             "the bread plate about 4-6 centimeters from the nearest edge"],
}

# ------------------------------------------------------------------ text generators


def random_char(rng: random.Random) -> str:
    """One character: mostly ASCII, often a special one, sometimes anything but a
    surrogate (astral planes included)."""
    k = rng.random()
    if k < 0.5:
        return chr(rng.randint(0x20, 0x7E))
    if k < 0.7:
        return rng.choice(SPECIAL_CHARS)
    if k < 0.8:
        return chr(rng.randint(0, 0x1F))
    while True:
        cp = rng.randint(0x80, 0xFFFF if k < 0.95 else 0x10FFFF)
        if not 0xD800 <= cp <= 0xDFFF:
            return chr(cp)


def random_text(rng: random.Random, max_len: int = 200) -> str:
    """Random Unicode of up to ``max_len`` characters."""
    return "".join(random_char(rng) for _ in range(rng.randint(0, max_len)))


def grammar_text(rng: random.Random, kind: str, max_words: int = 40) -> str:
    """Words from the grammar of ``kind``'s valid inputs, joined by random separators."""
    pools = _WORDS_BY_KIND[kind]
    words = [rng.choice(rng.choice(pools)) for _ in range(rng.randint(1, max_words))]
    seps = [" "] * 8 + [", ", "", "\n", ". ", " and "]
    return "".join(w + rng.choice(seps) for w in words)


def mutate(rng: random.Random, text: str, edits: int | None = None) -> str:
    """``text`` with a few random edits: characters or words inserted, deleted, repeated,
    swapped or replaced, case changed, cut short."""
    for _ in range(rng.randint(1, 6) if edits is None else edits):
        n = len(text)
        i, j = sorted((rng.randint(0, n), rng.randint(0, n)))
        op = rng.randrange(9)
        if op == 0:
            text = text[:i] + random_char(rng) + text[i:]
        elif op == 1:
            text = text[:i] + text[j:]
        elif op == 2:
            text = text[:j] + text[i:j] * rng.randint(1, 4) + text[j:]
        elif op == 3:
            text = text[:i] + rng.choice(SPECIAL_CHARS) + text[i + 1:]
        elif op == 4:
            text = text[:i] + text[i:j].upper() + text[j:]
        elif op == 5:
            text = text[:i]
        elif op == 6:
            pool = rng.choice([_NAMES, _PHRASES, NUMBERS, UNITS, _GLUE])
            text = text[:i] + " " + rng.choice(pool) + " " + text[i:]
        elif op == 7:
            text = text[i:j] + text[:i] + text[j:]
        else:
            text = text[:i] + rng.choice(["\n", "  ", "\t", ".", ",", "-", ":", "'"]) + text[i:]
    return text


def text_input(rng: random.Random, kind: str) -> str:
    """One input for a text parser: random Unicode, grammar, or a mutated valid input;
    now and then a long one."""
    k = rng.random()
    if k < 0.25:
        text = random_text(rng)
    elif k < 0.6:
        # Short requests: a long one almost always holds some count that counts nothing.
        text = grammar_text(rng, kind, 8 if kind == "request" else 40)
    else:
        text = mutate(rng, rng.choice(VALID[kind]))
    if rng.random() < 0.02:
        text = (text or "x") * rng.randint(2, 4_000 // max(len(text), 1) + 2)
    return text


# ------------------------------------------------------------------ structured files

_CATALOG_KEYS = ["objects", "name", "shape", "size", "height", "synonyms"]
_SCENE_KEYS = ["name", "room", "width", "depth", "walls", "center", "size", "yaw", "tables",
               "shape", "diameter", "height", "target", "source_tables", "sources", "object",
               "table", "position", "chairs", "chair_band_m", "robot", "start", "base_radius_m",
               "reach_min_m", "reach_max_m", "speed_mps", "turn_speed_radps", "pick_time_s",
               "place_time_s", "capacity", "diners"]
_RECORD_KEYS = ["backend", "model", "prompt", "response", "latency_s", "prompt_tokens",
                "completion_tokens", "seed"]
_SCALARS: list[object] = [None, True, False, 0, 1, -1, 2**70, -(2**70), 0.0, -0.0, 0.3, 1.2,
                          -5.5, 1e308, 1e-320, math.inf, -math.inf, math.nan, "", "box",
                          "circle", "rectangle", "dining table", "mug", "0.5", "[0.1, 0.1]"]


def random_value(rng: random.Random, keys: list[str], depth: int = 0) -> object:
    """A random YAML/JSON value: scalars of every type (inf, nan, huge ints), lists and
    mappings keyed by the file's own field names or by random text."""
    k = rng.random()
    if depth > 4 or k < 0.45:
        if rng.random() < 0.2:
            return random_text(rng, 20)
        if rng.random() < 0.3:
            return rng.uniform(-10, 10)
        return rng.choice(_SCALARS)
    if k < 0.7:
        return [random_value(rng, keys, depth + 1) for _ in range(rng.randint(0, 4))]
    out: dict[object, object] = {}
    for _ in range(rng.randint(0, 6)):
        key: object = rng.choice(keys) if rng.random() < 0.85 else (
            random_text(rng, 10) if rng.random() < 0.7 else rng.choice([0, 1.5, True, None]))
        out[key] = random_value(rng, keys, depth + 1)
    return out


def _entry(rng: random.Random, fields: dict[str, Callable[[], object]], keys: list[str]
           ) -> dict[str, object]:
    """A mapping with most of ``fields`` (each a valid value, or now and then a random one)."""
    out: dict[str, object] = {}
    for key, make in fields.items():
        if rng.random() < 0.9:
            out[key] = make() if rng.random() < 0.8 else random_value(rng, keys, 3)
    if rng.random() < 0.1:
        out[rng.choice(keys + ["colour"])] = random_value(rng, keys, 3)
    return out


def catalog_structure(rng: random.Random) -> object:
    """A catalog-like structure: mostly well-formed entries, with duplicate names and
    synonyms, wrong types, missing and extra fields."""
    if rng.random() < 0.15:
        return random_value(rng, _CATALOG_KEYS)
    names = [*rng.sample(CATALOG.names(), 3), "spork", "cup", "Mug", random_text(rng, 8)]

    def size() -> list[float]:
        d = rng.choice([0.1, 0.05, 0.0, -0.1, 1e9])
        return [d, d if rng.random() < 0.7 else d * 2]

    fields: dict[str, Callable[[], object]] = {
        "name": lambda: rng.choice(names), "shape": lambda: rng.choice(["circle", "box", "star"]),
        "size": size, "height": lambda: rng.choice([0.02, 0.1, 0.0, -1.0]),
        "synonyms": lambda: rng.sample(names + ["fork", "coaster", ""], rng.randint(0, 3))}
    return {"objects": [_entry(rng, fields, _CATALOG_KEYS) for _ in range(rng.randint(0, 6))]}


def scene_structure(rng: random.Random) -> object:
    """A scene-like structure: the packaged room with fields replaced, dropped or added."""
    if rng.random() < 0.15:
        return random_value(rng, _SCENE_KEYS)
    scene = yaml.safe_load(_SCENE_TEXT)
    for _ in range(rng.randint(1, 4)):
        node = scene
        for _ in range(rng.randint(0, 3)):
            if isinstance(node, dict) and node:
                child = node[rng.choice(list(node))]
            elif isinstance(node, list) and node:
                child = rng.choice(node)
            else:
                break
            if not isinstance(child, dict | list):
                break
            node = child
        value = random_value(rng, _SCENE_KEYS, 2)
        if isinstance(node, dict):
            key = rng.choice(list(node) or _SCENE_KEYS) if rng.random() < 0.8 \
                else rng.choice(_SCENE_KEYS)
            if rng.random() < 0.2:
                node.pop(key, None)
            else:
                node[key] = value
        elif isinstance(node, list) and node:
            node[rng.randrange(len(node))] = value
    return scene


def record_line(rng: random.Random) -> str:
    """One JSONL line of a replay file: a record, a damaged one, or junk."""
    k = rng.random()
    if k < 0.5:
        record: dict[str, object] = {"backend": "embedded", "model": "m", "prompt": "p",
                                     "response": "Place the fork.", "latency_s": 0.5,
                                     "prompt_tokens": 3, "completion_tokens": 4, "seed": 1}
        for _ in range(rng.randint(0, 3)):
            key = rng.choice(_RECORD_KEYS + ["extra"])
            if rng.random() < 0.3:
                record.pop(key, None)
            else:
                record[key] = random_value(rng, _RECORD_KEYS, 3)
        return json.dumps(record, ensure_ascii=rng.random() < 0.5)
    if k < 0.7:
        return json.dumps(random_value(rng, _RECORD_KEYS), ensure_ascii=False)
    return random_text(rng, 60)


def _dump(rng: random.Random, value: object) -> str:
    try:
        return yaml.safe_dump(value, allow_unicode=rng.random() < 0.5,
                              default_flow_style=rng.choice([None, True, False]))
    except yaml.YAMLError:  # e.g. a key the dumper cannot represent
        return repr(value)


#: YAML that is valid text but strange data, and YAML that is broken.
YAML_ODDITIES = [
    "a: &a [*a]\nobjects: *a\n", "objects: &o\n  - *o\n", "? [1, 2]\n: x\n",
    "objects: !!python/object:os.system {}\n", "objects: !!binary 'not base64'\n",
    "objects: !!timestamp 2024-13-45\n", "objects: !!float abc\n", "objects: !!int 0x\n",
    "objects: !!set {a, b}\n", "<<: {objects: []}\n", "objects: [" * 3_000 + "]" * 3_000,
    "objects:\n" + "  - " * 500 + "x\n", "%YAML 9.9\n---\nobjects: []\n", "--- a\n--- b\n",
    "objects: [{name: mug, shape: circle, size: [.nan, .nan], height: .inf}]\n",
    "objects: [{name: \"a\\nb\", shape: box, size: [1, 1], height: 1, \"x\\ny\": 1}]\n",
    "\t\x00objects", "\ufeffobjects: []\n", "objects: {}\n", "objects: 'x' 'y'\n",
    "room: {width: 1e400, depth: -0}\ntables: []\ntarget: x\n",
]
_YAML_TAGS = ["int", "float", "bool", "timestamp", "binary", "null", "str", "set", "omap",
              "pairs", "map", "seq", "merge", "value", "python/tuple", "python/name:os.system"]
_CATALOG_TEXT = resources.files("llm_grop").joinpath("data/catalog.yaml").read_text("utf-8")
_SCENE_TEXT = resources.files("llm_grop").joinpath(
    "data/scenes/dining_room.yaml").read_text("utf-8")
_RECORD_TEXT = "\n".join(record_line(random.Random(k)) for k in range(3))


def file_input(rng: random.Random, kind: str) -> Input:
    """One input for a file parser (``kind`` "catalog", "scene", "replay" or
    "preference_file"): YAML or JSONL text, or now and then bytes that are not UTF-8."""
    k = rng.random()
    if kind == "replay":
        text = "\n".join(record_line(rng) for _ in range(rng.randint(0, 4)))
        if k < 0.3:
            text = mutate(rng, text or _RECORD_TEXT)
    elif kind == "preference_file":
        value: object = {"preferences": [grammar_text(rng, "preferences", 8)
                                         for _ in range(rng.randint(0, 3))]} \
            if k < 0.5 else random_value(rng, ["preferences"])
        text = _dump(rng, value) if k < 0.9 else rng.choice(YAML_ODDITIES).replace(
            "objects", "preferences")
        if rng.random() < 0.3:
            text = mutate(rng, text)
    else:
        valid = _CATALOG_TEXT if kind == "catalog" else _SCENE_TEXT
        structure = catalog_structure if kind == "catalog" else scene_structure
        if k < 0.45:
            text = _dump(rng, structure(rng))
        elif k < 0.75:
            text = mutate(rng, valid)
        elif k < 0.85:
            text = rng.choice(YAML_ODDITIES)
        else:
            text = random_text(rng)
    if rng.random() < 0.1 and kind != "replay":
        # A YAML tag before some value: PyYAML converts tagged scalars itself.
        at = rng.randint(0, len(text))
        text = f"{text[:at]} !!{rng.choice(_YAML_TAGS)} {text[at:]}"
    if rng.random() < 0.05:
        data = bytearray(text.encode("utf-8"))
        for _ in range(rng.randint(1, 3)):
            data.insert(rng.randint(0, len(data)), rng.choice([0xFF, 0xC3, 0x80, 0xED, 0xFE]))
        return bytes(data)
    return text
