"""What the two websites share (:mod:`llm_grop.web`): which bodies are JSON, and how deep
a JSON body nests, counted on its bytes."""

from __future__ import annotations

import json
import random
from typing import Any

import pytest

from llm_grop.web import is_json, json_problem

#: Strings that look like brackets and escapes, which must not count as nesting.
TRICKY = ["[", "{", "]}", '"[', "\\", '\\"[{', "}]\\\\", ""]


def depth(value: Any) -> int:
    """How deep ``value``'s lists and dicts nest (a list is 1, a scalar 0)."""
    if isinstance(value, dict):
        return 1 + max(map(depth, value.values()), default=0)
    if isinstance(value, list):
        return 1 + max(map(depth, value), default=0)
    return 0


def random_value(rng: random.Random, level: int = 0) -> Any:
    draw = rng.random()
    if level > 10 or draw < 0.3:
        return rng.choice([1, 2.5, None, True, *TRICKY])
    if draw < 0.65:
        return [random_value(rng, level + 1) for _ in range(rng.randint(0, 3))]
    return {rng.choice(TRICKY) + str(k): random_value(rng, level + 1)
            for k in range(rng.randint(0, 3))}


def test_depth_is_counted_as_the_parsed_value_nests() -> None:
    rng = random.Random(0)
    for _ in range(2000):
        value = random_value(rng)
        body = json.dumps(value, ensure_ascii=rng.random() < 0.5).encode()
        for limit in (1, 2, 3, 5, 8):
            refused = json_problem(body, limit) is not None
            assert refused == (depth(value) > limit), (body, limit)


@pytest.mark.parametrize(("content_type", "json_"), [
    (b"application/json", True), (b"Application/JSON; charset=utf-8", True),
    (b"application/problem+json", True), (b"application/jsonx", False),
    (b"text/json", False), (b"text/plain+json", False), (b"json", False), (None, False)])
def test_only_application_json_and_its_suffix_are_json(content_type: bytes | None,
                                                        json_: bool) -> None:
    assert is_json(content_type) is json_
