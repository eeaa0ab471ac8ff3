"""Logical consistency of symbolic relations with clingo (paper §III-A).

The rules are in ``relations.lp``. Object names never enter ASP source: objects
and lines are passed as integers, so any name is safe.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources

import clingo

from llm_grop.world.relation import (
    ABOVE,
    ABOVE_LEFT,
    ABOVE_RIGHT,
    BELOW,
    BELOW_LEFT,
    BELOW_RIGHT,
    CENTER,
    LEFT,
    ON_TOP_OF,
    RIGHT,
    UNDER,
    Relation,
)

#: Contract relation name -> ASP constant.
ASP_NAME = {
    LEFT: "left", RIGHT: "right", ABOVE: "above", BELOW: "below",
    ABOVE_LEFT: "above_left", ABOVE_RIGHT: "above_right",
    BELOW_LEFT: "below_left", BELOW_RIGHT: "below_right",
    ON_TOP_OF: "on_top_of", UNDER: "under",
}


@dataclass(frozen=True)
class ConsistencyReport:
    """Whether relations are consistent; if not, a minimal conflicting subset (input order)."""

    consistent: bool
    conflict: tuple[Relation, ...] = ()


@functools.lru_cache(maxsize=1)
def _rules() -> str:
    return resources.files("llm_grop.arrangement").joinpath("relations.lp").read_text("utf-8")


def _facts(relations: Sequence[Relation]) -> str:
    ids: dict[str, int] = {}
    out = []
    for i, r in enumerate(relations):
        s = ids.setdefault(r.subject, len(ids))
        if r.relation == CENTER:
            out.append(f"stated_center({i},{s}).")
        else:
            o = ids.setdefault(r.reference or "", len(ids))
            out.append(f"stated({i},{s},{ASP_NAME[r.relation]},{o}).")
    return "\n".join(out)


class _Solver:
    """One grounding of the rules and facts; subsets are checked with assumptions."""

    def __init__(self, relations: Sequence[Relation], largest: bool = False) -> None:
        self.n = len(relations)
        self.ctl = clingo.Control(["--warn=none"])
        self.ctl.add("base", [], _facts(relations) + "\n" + _rules())
        parts = [("base", [])]
        if largest:
            self.ctl.configuration.solve.opt_mode = "opt"
            parts.append(("largest", [clingo.Number(self.n)]))
        self.ctl.ground(parts)
        self.keep = [self.ctl.symbolic_atoms[clingo.Function("keep", [clingo.Number(i)])]
                     for i in range(self.n)]

    def consistent(self, subset: Sequence[int]) -> tuple[bool, list[int]]:
        """Whether the lines in ``subset`` are consistent, and the unsat core's lines if not."""
        chosen = set(subset)
        assumptions = [(clingo.Function("keep", [clingo.Number(i)]), i in chosen)
                       for i in range(self.n) if self.keep[i] is not None]
        core: list[int] = []
        result = self.ctl.solve(assumptions=assumptions,
                                on_core=lambda lits: core.extend(lits))
        if result.satisfiable:
            return True, []
        literal_to_line = {self.keep[i].literal: i for i in chosen if self.keep[i] is not None}
        return False, sorted(literal_to_line[lit] for lit in core if lit in literal_to_line)


def check(relations: Sequence[Relation]) -> ConsistencyReport:
    """Check ``relations``; when inconsistent, report a minimal conflicting subset."""
    if not relations:
        return ConsistencyReport(True)
    solver = _Solver(relations)
    ok, core = solver.consistent(range(len(relations)))
    if ok:
        return ConsistencyReport(True)
    return ConsistencyReport(False, tuple(relations[i] for i in _shrink(solver, core)))


def minimal_conflict(relations: Sequence[Relation]) -> tuple[Relation, ...]:
    """A minimal conflicting subset: inconsistent, while every proper subset is consistent.

    Starts from clingo's unsat core and drops lines one by one while the rest
    still conflicts. Empty when ``relations`` are consistent.
    """
    return check(relations).conflict


def _shrink(solver: _Solver, core: list[int]) -> list[int]:
    """Deletion-based minimisation: drop each line whose removal keeps the conflict."""
    core = core or list(range(solver.n))
    for i in list(core):
        trial = [j for j in core if j != i]
        if not solver.consistent(trial)[0]:
            core = trial
    return core


def largest_consistent_subset(relations: Sequence[Relation]) -> tuple[Relation, ...]:
    """The most relations that are consistent together (earlier lines win ties), in order."""
    if not relations:
        return ()
    solver = _Solver(relations, largest=True)
    best: list[int] = []

    def on_model(model: clingo.Model) -> None:
        best[:] = sorted(s.arguments[0].number for s in model.symbols(shown=True)
                         if s.name == "keep")

    solver.ctl.solve(on_model=on_model)
    return tuple(relations[i] for i in best)
