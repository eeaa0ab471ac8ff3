"""The style benchmark of issue 42: a way of setting the table shown in a few example
settings, learned (``llm-grop learn``), then asked of held-out requests whose objects the
examples partly do not show (``data/styles.yaml``).

Per style, its example settings are arranged from the style's own sentences (one per
seed, no LLM asked) and learned from twice: exactly (``--exact``, no LLM) and with the LLM
step (rules for the catalog's other objects). Each held-out request is then arranged with
the learned file for ``--seeds`` seeds, and every relation the style expects of it is
checked where the objects were placed (the one meaning of each relation; a style's
``min_gap_cm`` also asks that gap). Printed per style and learning: the share of expected
relations kept, for objects the examples show (``seen``) and for relations with an object
they do not (``unseen``). The LLM, for the rules and for Template 1 and its questions, is

* ``stand-in`` (default): a local OpenAI-compatible server on 127.0.0.1 answering as a
  capable model would: the style's hand-written ``rules``, and the ``usual`` relations
  to Template 1; hand-written answers, not a model's output, labelled so;
* ``embedded``: the embedded model (SmolLM2-135M), run live; needs it installed.
Then the usual style (``data/preferences.yaml``) is learned exactly from 2 example
settings (``usual_examples``: one of a plate and its cutlery, mug, lid and bread plate, one
of a bowl, strawberry, mug on its mat, bread plate, bread and water cup), and LLM-GROP runs
the paper's 8 tasks x ``--paper-seeds`` in 2D (1 chair) with it as ``--preferences``, and
with the hand-written file, the stand-in answering Template 1 the usual way
(``feedback_paper.py --llm stand-in``'s): the automatic rating per task, each way.
Run: .venv/bin/python benchmarks/style_learning.py [--seeds 5] [--llm stand-in|embedded]
     [--paper-seeds 20] [--quick]
"""

from __future__ import annotations

import argparse
import re
import tempfile
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import yaml
from common import chat_server, parse_args, span, write_settings
from feedback_paper import DATA, said, stand_in_answer
from hard_scenes import outcome
from hard_scenes import stand_in as scene_stand_in

from llm_grop import BackendOptions, arrange, learn, run
from llm_grop.arrangement.examples import observed_gap_m, relation_between
from llm_grop.arrangement.preferences import load_preference_file, read_preferences
from llm_grop.errors import LLMGropError
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import STACKING
from llm_grop.world.request import items_from_names

STYLES = Path(__file__).parent / "data" / "styles.yaml"


def place_line(sentence: str) -> str:
    """A preference sentence as Template 1's line: "Place the X ...."."""
    return "Place " + sentence + "."


def named(text: str, catalog: Catalog) -> list[str]:
    """The catalog objects ``text`` lists as Template 1 does ("a X, a Y, and a Z")."""
    return [n for n in catalog.names()
            if re.search(rf"\ban? {re.escape(n)}(?=,| and|\.| on|$)", text, re.M)]


def stand_in(usual: Sequence[str], rules: str, catalog: Catalog) -> Callable[[Any], str]:
    """The stand-in's reply: ``rules`` to the generalisation prompt, the ``usual``
    relations among the objects asked about to Template 1 and its follow-ups, 3 cm to
    every distance."""
    def reply(body: dict[str, Any]) -> str:
        prompt = body["messages"][-1]["content"]
        if "Other objects they may ask for" in prompt:
            return rules
        if "centimeters" in prompt.lower():
            return "About 3 centimeters."
        missing = re.search(r"Where should an? (.+?) be placed in relation to", prompt)
        asked = [missing.group(1)] if missing else named(prompt.split("\n")[-1], catalog)
        lines = [place_line(s) for s in usual
                 if s.startswith("the ") and any(s.startswith(f"the {n} ") for n in asked)
                 and all(n in asked or not re.search(rf"\bthe {re.escape(n)}\b", s)
                         for n in catalog.names() if n not in asked)]
        return "\n".join(lines) or "Place the dinner plate in the center of the table."
    return reply


def kept(expected: str, placed: Mapping[str, Any], names: Sequence[str], catalog: Catalog,
         min_gap_cm: float | None) -> bool:
    """Whether ``expected`` (a sentence) holds between the objects as ``placed``."""
    (want,) = read_preferences((), (expected,), items_from_names(list(names), catalog),
                               catalog).relations
    assert want.reference is not None
    s, r = placed[want.subject], placed[want.reference]
    if relation_between(s, r) != want.relation:
        return False
    return min_gap_cm is None or want.relation in STACKING \
        or observed_gap_m(want.relation, s, r) >= min_gap_cm / 100 - 1e-9


def score(style: Mapping[str, Any], prefs: Path, llm: dict[str, Any], seeds: int,
          catalog: Catalog) -> tuple[list[int], list[int], list[str]]:
    """Expected relations kept and asked, ``[seen, unseen]``, over the held-out requests
    arranged with ``prefs``; and the errors of runs that ended without an arrangement."""
    shown = {it.name for it in items_from_names(_objects(style["examples"], catalog), catalog)}
    got, asked, errors = [0, 0], [0, 0], []
    for held in style["held_out"]:
        names = _objects(held["request"], catalog)
        for seed in range(seeds):
            try:
                a = arrange(held["request"], seed=seed, catalog=catalog,
                            preferences_file=str(prefs), **llm).arrangement
            except LLMGropError as exc:
                errors.append(str(exc).splitlines()[0])
                continue
            placed = {p.name: p for p in a.placements}
            for sentence in held["expected"]:
                k = 0 if all(n in shown for n in names if re.search(
                    rf"\bthe {re.escape(n)}\b", sentence)) else 1
                asked[k] += 1
                got[k] += kept(sentence, placed, names, catalog, held.get("min_gap_cm"))
    return got, asked, errors


def paper_ratings(prefs: Path, seeds: int, tasks: Sequence[int], state: Any
                  ) -> list[float | None]:
    """The mean automatic rating per task of LLM-GROP with ``prefs`` as preferences, the
    stand-in (``state``) answering Template 1 the usual way (``None``: nothing executed)."""
    out = []
    for task in tasks:
        state.reply = scene_stand_in(said(stand_in_answer(task)))
        ratings = []
        for seed in range(seeds):
            try:
                r = run(task=task, seed=seed, chairs=1, method="llm-grop", llm="openai",
                        llm_options=BackendOptions(base_url=state.url, api_key="stand-in",
                                                   max_retries=0),
                        preferences_file=str(prefs))
            except LLMGropError:
                continue
            ratings.append(outcome(r).rating)
        out.append(sum(ratings) / len(ratings) if ratings else None)
    return out


def _objects(request: str, catalog: Catalog) -> list[str]:
    return named(request.replace(" and ", ", and "), catalog)


def _share(got: int, asked: int) -> str:
    return f"{got}/{asked} ({100 * got / asked:.0f} %)" if asked else "-"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--llm", default="stand-in", choices=("stand-in", "embedded"))
    ap.add_argument("--paper-seeds", type=int, default=20)
    ap.add_argument("--tasks", default="1-8", help="the paper's tasks to rate (1-8)")
    args = parse_args(ap, {"seeds": 1, "paper_seeds": 1, "tasks": "1"})
    data = yaml.safe_load(STYLES.read_text(encoding="utf-8"))
    catalog = Catalog.load(use_env=False)
    state, httpd = chat_server()
    who = ("a local server answering as a capable model would (the styles' rules and the "
           "usual relations: hand-written answers, not a model's output)"
           if args.llm == "stand-in" else "the embedded model (SmolLM2-135M), run live")
    llm: dict[str, Any] = {"llm": "openai", "llm_options": BackendOptions(
        base_url=state.url, api_key="stand-in", max_retries=0)} \
        if args.llm == "stand-in" else {"llm": "embedded"}
    print(f"style benchmark, {args.seeds} seeds per held-out request; LLM: {who}")
    try:
        with tempfile.TemporaryDirectory() as scratch:
            for style in data["styles"]:
                where = Path(scratch) / style["name"].replace(" ", "-")
                where.mkdir()
                state.reply = stand_in(data["usual"], style["rules"], catalog)
                files = write_settings(where, style["examples"], style["sentences"],
                                       style["seeds"], catalog)
                print(f"{style['name']}: {len(files)} example settings of "
                      f"{style['examples']!r}")
                for label, generalise in (("exact, no LLM step", False),
                                          ("with the LLM step", True)):
                    learned = learn(files, catalog=catalog, generalise=generalise, **llm)
                    prefs = where / f"{generalise}.yaml"
                    prefs.write_text(learned.preference_file(), encoding="utf-8")
                    got, asked, errors = score(style, prefs, llm, args.seeds, catalog)
                    rules = sum(s.sources[0].startswith("a rule")
                                for s in learned.sentences)
                    print(f"  {label}: {len(learned.sentences)} sentences ({rules} rules); "
                          f"relations kept, seen {_share(got[0], asked[0])}, unseen "
                          f"{_share(got[1], asked[1])}"
                          + (f"; {len(errors)} runs without an arrangement" if errors
                             else ""))
                    for e in sorted(set(errors))[:2]:
                        print(f"    {e[:160]}")
            where = Path(scratch) / "usual"
            where.mkdir()
            hand = DATA / "preferences.yaml"
            pool = load_preference_file(hand)
            files = []
            for k, request in enumerate(data["usual_examples"]):
                (where / str(k)).mkdir()
                files += write_settings(where / str(k), request, pool, (1,), catalog)
            learned = learn(files, catalog=catalog)
            prefs = where / "learned.yaml"
            prefs.write_text(learned.preference_file(), encoding="utf-8")
            tasks = span(args.tasks)
            print(f"the usual style learned from {len(files)} example settings "
                  f"({len(learned.sentences)} sentences, exact); LLM-GROP, the paper's tasks "
                  f"x {args.paper_seeds} seeds, 2D, 1 chair, the stand-in answering "
                  "Template 1 the usual way; automatic rating per task:")
            for label, path in (("hand-written preferences.yaml", hand), ("learned", prefs)):
                got = paper_ratings(path, args.paper_seeds, tasks, state)
                print(f"  {label}: " + ", ".join(
                    f"{t}: {'-' if g is None else f'{g:.2f}'}"
                    for t, g in zip(tasks, got, strict=True)))
    finally:
        httpd.shutdown()


if __name__ == "__main__":
    main()
