"""The automatic rater: scores an arrangement 1-5 the way the paper's raters did.

:func:`rate` reads the contract's arrangement JSON (a dict, from any system or
written by hand), applies the place-setting conventions of ``conventions.yaml``
(rules in :mod:`llm_grop.evaluation.rules` and :mod:`~llm_grop.evaluation.cutlery`,
documented in docs/rater.md) and maps the failed checks to the paper's Table III
scale (Ding et al., IROS 2023):

====  ==========================================================================
5     no check failed: all items present, arranged very neatly (a waiter's standard)
4     only minor failures, one or two (alignment, spacing, a small angle, ...)
3     exactly one major failure (an overlap, a wrong side, a wrong stack, badly
      off-centre, ...), or more than two minor ones
2     two or more major failures: poor, major adjustments needed
1     a requested item is missing, or an object is off the table (its centre
      outside the top, or more than 20 % of it hanging over an edge)
====  ==========================================================================

Every failure counts once: a fault of two objects (say both cutlery pieces on the
wrong side) is two failures. Rules whose reference object is absent are skipped,
never failed. The rater never reads ``relations`` or ``llm``: it judges where
objects are, not what a planner meant. Lengths are metres, angles radians.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

from llm_grop.contract.models import ArrangementDoc, CheckDoc, RatingDoc
from llm_grop.contract.serialize import read_doc
from llm_grop.errors import BadInput
from llm_grop.evaluation.context import make_context
from llm_grop.evaluation.conventions import Conventions, load_conventions
from llm_grop.evaluation.diners import diner_docs, per_diner_kinds, several_diners
from llm_grop.evaluation.model import Check, Setting, kind_of, read_setting
from llm_grop.evaluation.rules import RULES
from llm_grop.language.request import parse_request
from llm_grop.world.catalog import Catalog

#: The arrangement JSON's fields the rater reads.
_RATED = ("request", "table", "objects", "request_read_by")

#: What each score means (Table III of the paper, shortened).
SCORE_MEANING = {
    1: "an item is missing or off the table",
    2: "poor: major adjustments needed",
    3: "fair: significant room to improve",
    4: "neat: a waiter might make minor adjustments",
    5: "very neat: meets an experienced waiter's standard",
}


@dataclass(frozen=True)
class Rating:
    """A score from 1 to 5, every check behind it, and a one-line summary. A table set for
    several diners also has each diner's rating (``diners``); its score is the lowest."""

    score: int
    checks: tuple[Check, ...]
    summary: str
    diners: tuple[Rating, ...] = ()

    @property
    def failed(self) -> tuple[Check, ...]:
        """The checks that failed, in report order."""
        return tuple(c for c in self.checks if not c.passed)

    def doc(self) -> RatingDoc:
        """The rating as the contract's document (a trial row's ``rating_explanation``)."""
        extra = {"diners": [d.doc() for d in self.diners]} if self.diners else {}
        return RatingDoc(score=self.score, summary=self.summary,
                         checks=[CheckDoc(**asdict(c)) for c in self.checks], **extra)

    def to_dict(self) -> dict[str, Any]:
        """``{"score", "summary", "checks": [...]}``, ready for JSON."""
        return self.doc().to_json()


def score_of(checks: Sequence[Check]) -> int:
    """The Table III score that ``checks`` earn (see the module docstring)."""
    failed = [c for c in checks if not c.passed]
    if any(c.severity == "missing" for c in failed):
        return 1
    major = sum(c.severity == "major" for c in failed)
    minor = sum(c.severity == "minor" for c in failed)
    if major >= 2:
        return 2
    if major == 1 or minor > 2:
        return 3
    return 4 if minor else 5


def _summary(score: int, checks: Sequence[Check]) -> str:
    failed = [c for c in checks if not c.passed]
    counts = {sev: sum(c.severity == sev for c in failed) for sev in ("missing", "major", "minor")}
    if not failed:
        ran = sum(not c.skipped for c in checks)
        return f"{score}/5: {SCORE_MEANING[score]} ({ran} checks passed)"
    parts = [f"{n} {sev}" for sev, n in counts.items() if n]
    return f"{score}/5: {SCORE_MEANING[score]} ({', '.join(parts)} failure" \
           f"{'s' * (len(failed) > 1)}; first: {failed[0].name}: {failed[0].detail})"


def requested_kinds(names: Sequence[str], catalog: Catalog) -> tuple[str, ...]:
    """Catalog kinds of item names; ``"dinner fork 2"`` counts as another dinner fork."""
    if isinstance(names, str):
        raise BadInput("requested: expected a list of object names, got one string")
    out = []
    for i, name in enumerate(names):
        if not isinstance(name, str) or not name.strip():
            raise BadInput(f"requested[{i}]: expected an object name, got {name!r}")
        out.append(kind_of(name, catalog))
    return tuple(out)


def rate(arrangement: Mapping[str, Any] | ArrangementDoc, requested: Sequence[str] | None = None,
         catalog: Catalog | None = None, *, conventions: Conventions | None = None,
         where: str = "arrangement") -> Rating:
    """Score ``arrangement`` (the contract's arrangement JSON, as a dict or a validated
    :class:`~llm_grop.contract.models.ArrangementDoc`) from 1 to 5.

    ``requested`` are catalog item names ("dinner fork", "dinner fork 2", a synonym
    such as "fork"); when ``None`` they are read from the JSON's ``request`` text
    (and the presence check is skipped if there is none). ``catalog`` resolves
    names (default: the packaged catalog and ``$LLM_GROP_CATALOG``);
    ``conventions`` replaces the packaged ``conventions.yaml``. ``where`` prefixes
    error messages.

    Raises :class:`~llm_grop.errors.BadInput` (one line naming the field) for a
    malformed arrangement, and for a request that names unknown objects.
    """
    catalog = catalog if catalog is not None else Catalog.load()
    conv = conventions if conventions is not None else load_conventions()
    if isinstance(arrangement, ArrangementDoc):
        doc = arrangement
    elif isinstance(arrangement, Mapping):
        # Only what the rater judges is validated: a malformed `relations` or `llm` is the
        # planner's business, not the table's.
        doc = read_doc(ArrangementDoc, {k: arrangement[k] for k in _RATED if k in arrangement},
                       where)
    else:
        raise BadInput(f"{where}: expected a JSON object with 'table' and 'objects'")
    kinds: tuple[str, ...] | None
    assigned: list[tuple[str, int | None]] | None = None
    if requested is not None:
        kinds = requested_kinds(requested, catalog)
    elif doc.request.strip() and doc.request_read_by != "llm":
        parsed = parse_request(doc.request, catalog).items
        kinds = tuple(i.kind for i in parsed)
        assigned = [(i.kind, i.diner) for i in parsed]
    else:
        # An LLM read (part of) this request; without it, the objects on the table are
        # what was asked for.
        kinds = None
    if several_diners(doc):
        return _rate_diners(doc, kinds, assigned, catalog, conv, where)
    setting = read_setting(doc, kinds, catalog, conv, where)
    return _rate(setting)


def _rate(setting: Setting) -> Rating:
    ctx = make_context(setting)
    checks = tuple(c for rule in RULES for c in rule(setting, ctx))
    score = score_of(checks)
    return Rating(score, checks, _summary(score, checks))


def _rate_diners(doc: ArrangementDoc, kinds: tuple[str, ...] | None,
                 assigned: list[tuple[str, int | None]] | None, catalog: Catalog,
                 conv: Conventions, where: str) -> Rating:
    """Each diner's setting rated in their frame; the table scores the lowest of them."""
    docs = diner_docs(doc, where)
    wanted = per_diner_kinds(kinds, len(docs), assigned)
    ratings = [_rate(read_setting(sub, want, catalog, conv, f"{where}: diner {k}", top))
               for k, ((sub, top), want) in enumerate(zip(docs, wanted, strict=True))]
    score = min(r.score for r in ratings)
    worst = min(range(len(ratings)), key=lambda k: ratings[k].score)
    checks = tuple(replace(c, detail=f"diner {k}: {c.detail}")
                   for k, r in enumerate(ratings) for c in r.checks)
    each = ", ".join(str(r.score) for r in ratings)
    if len(ratings) == 1:
        return Rating(score, checks, f"diner 0: {ratings[0].summary}", tuple(ratings))
    summary = (f"{score}/5: lowest of {len(ratings)} settings (diner {worst}); per diner "
               f"{each}; diner {worst}: {ratings[worst].summary}")
    return Rating(score, checks, summary, tuple(ratings))
