"""The automatic rater: the paper's 1-5 rating (Table III) of a table arrangement.

``rate(arrangement_json)`` scores the contract's arrangement JSON of any system
against place-setting conventions kept as data in ``conventions.yaml`` (see
docs/rater.md)::

    from llm_grop.evaluation import rate
    rating = rate(json.load(open("t.json")))
    print(rating.score, rating.summary)
    for check in rating.failed:
        print(check.name, check.severity, check.detail)

This package is for evaluation only. Planning code (``arrangement``,
``planning``, ``methods``, ``simulation``) must never import it: the conventions
it knows are the answer the LLM is asked for.
"""

from llm_grop.evaluation.model import Check
from llm_grop.evaluation.rater import Rating, rate

__all__ = ["Check", "Rating", "rate"]
