"""Logical consistency of symbolic relations with clingo (paper §III-A).

The rules, and what each relation means on the table's two axes, are in
``relations.lp``. Object names never enter ASP source: objects and lines are
passed to clingo as integers and mapped back in Python, so any name is safe.

*Minimal conflict* here means: the lines are inconsistent together, and every
proper subset of them is consistent. It is found from clingo's unsat core
(assumptions on ``keep(I)``) and then shrunk by deletion. Deletion alone
guarantees this only for monotone rules; the one non-monotone rule (a stacking
line can allow two objects at the centre) involves ``center`` lines that take
part in no other rule, which keeps the guarantee (see :func:`_shrink`).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources

import clingo
from clingo import ast

from llm_grop.world.relation import (
    ABOVE,
    ABOVE_LEFT,
    ABOVE_RIGHT,
    BELOW,
    BELOW_LEFT,
    BELOW_RIGHT,
    LEFT,
    ON_TOP_OF,
    RIGHT,
    UNDER,
    Relation,
)

#: Contract relation name -> the ASP constant ``relations.lp`` uses for it.
ASP_NAME: dict[str, str] = {
    LEFT: "left", RIGHT: "right", ABOVE: "above", BELOW: "below",
    ABOVE_LEFT: "above_left", ABOVE_RIGHT: "above_right",
    BELOW_LEFT: "below_left", BELOW_RIGHT: "below_right",
    ON_TOP_OF: "on_top_of", UNDER: "under",
}

_Parts = list[tuple[str, Sequence[clingo.Symbol]]]


@dataclass(frozen=True)
class ConsistencyReport:
    """Whether relations are consistent together.

    ``conflict`` is a minimal conflicting subset in input order: inconsistent, while
    every proper subset is consistent. Empty when ``consistent``.
    """

    consistent: bool
    conflict: tuple[Relation, ...] = ()


@functools.lru_cache(maxsize=1)
def _rules() -> tuple[ast.AST, ...]:
    """The statements of ``relations.lp``, read and parsed once per process."""
    text = resources.files("llm_grop.arrangement").joinpath("relations.lp").read_text("utf-8")
    statements: list[ast.AST] = []
    ast.parse_string(text, statements.append)
    return tuple(statements)


def _facts(relations: Sequence[Relation]) -> str:
    """``stated``/``stated_center`` facts for ``relations``; names become integer ids."""
    ids: dict[str, int] = {}
    out = []
    for i, r in enumerate(relations):
        s = ids.setdefault(r.subject, len(ids))
        if r.reference is None:
            out.append(f"stated_center({i},{s}).")
        else:
            o = ids.setdefault(r.reference, len(ids))
            out.append(f"stated({i},{s},{ASP_NAME[r.relation]},{o}).")
    return "\n".join(out)


def _grounded(facts: str, parts: _Parts, optimise: bool = False) -> clingo.Control:
    """A clingo control with the rules and ``facts`` added and ``parts`` grounded."""
    ctl = clingo.Control(["--warn=none"])
    if optimise:
        ctl.configuration.solve.opt_mode = "opt"  # type: ignore[union-attr]
    ctl.add("base", [], facts)
    # Re-using the parsed rules saves re-parsing them for every check.
    with ast.ProgramBuilder(ctl) as builder:
        for statement in _rules():
            builder.add(statement)
    ctl.ground(parts)
    return ctl


class _Lines:
    """One grounding where every line may be dropped; subsets are tried by assumptions."""

    def __init__(self, facts: str, n: int) -> None:
        self.ctl = _grounded(facts, [("base", []), ("choose", [])])
        atoms = self.ctl.symbolic_atoms
        self.literal = [atoms[clingo.Function("keep", [clingo.Number(i)])].literal  # type: ignore[union-attr]
                        for i in range(n)]

    def conflict_core(self, subset: Sequence[int]) -> list[int] | None:
        """``None`` if the lines in ``subset`` are consistent, else the lines of an unsat core.

        The core's lines (kept, every other line dropped) are inconsistent.
        """
        chosen = set(subset)
        assumptions = [lit if i in chosen else -lit for i, lit in enumerate(self.literal)]
        core: list[int] = []
        result = self.ctl.solve(assumptions=assumptions, on_core=core.extend)
        if result.satisfiable:
            return None
        line_of = {self.literal[i]: i for i in chosen}
        return sorted(line_of[lit] for lit in core if lit in line_of)


def _shrink(lines: _Lines, core: list[int]) -> list[int]:
    """Deletion-based minimisation: drop each line whose removal leaves a conflict.

    Every line of the result is needed: dropping any one makes the rest consistent.
    That also makes every smaller subset consistent. The rules other than the
    centre rule are monotone (dropping lines cannot create their conflicts). If the
    result conflicts by a monotone rule, no ``center`` line can be in it (they feed
    only the centre rule, so dropping one would leave the conflict); then only
    monotone rules apply to its subsets. If it conflicts only by the centre rule,
    two ``center`` lines on an unstacked pair suffice, so the result is exactly
    those two lines.
    """
    for i in list(core):
        trial = [j for j in core if j != i]
        if lines.conflict_core(trial) is not None:
            core = trial
    return core


def check(relations: Sequence[Relation]) -> ConsistencyReport:
    """Whether ``relations`` are consistent; if not, with a minimal conflicting subset."""
    if not relations:
        return ConsistencyReport(True)
    facts = _facts(relations)
    # Common case first: with every line kept the grounder decides on its own.
    if _grounded(facts, [("base", []), ("all", [])]).solve().satisfiable:
        return ConsistencyReport(True)
    lines = _Lines(facts, len(relations))
    core = lines.conflict_core(range(len(relations)))
    if core is None:  # cannot happen: the same program was just unsatisfiable
        raise AssertionError("clingo found the relations consistent on a second look")
    return ConsistencyReport(False, tuple(relations[i] for i in _shrink(lines, core)))


def minimal_conflict(relations: Sequence[Relation]) -> tuple[Relation, ...]:
    """A minimal conflicting subset of ``relations``, in input order; empty if consistent.

    Minimal: the subset is inconsistent and no proper subset of it is.
    """
    return check(relations).conflict


def largest_consistent_subset(relations: Sequence[Relation]) -> tuple[Relation, ...]:
    """The largest consistent subset of ``relations``, in input order.

    Found by clingo optimisation over which lines to keep. Among subsets of the same
    size the one keeping earlier lines wins (line 0 if possible, then line 1, ...),
    so the answer is unique and deterministic.
    """
    if not relations:
        return ()
    n = len(relations)
    facts = _facts(relations)
    ctl = _grounded(facts, [("base", []), ("choose", []), ("largest", [clingo.Number(n)])],
                    optimise=True)
    best: list[int] = []

    def on_model(model: clingo.Model) -> None:
        best[:] = sorted(s.arguments[0].number for s in model.symbols(shown=True)
                         if s.name == "keep")

    ctl.solve(on_model=on_model)
    return tuple(relations[i] for i in best)
