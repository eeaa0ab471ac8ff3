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

What each relation means is not written here or in ``relations.lp``: it is the relations
table (``world/relations.yaml``), which :func:`_table_facts` turns into ``axis/3``,
``converse/2`` and ``rests/2`` facts for the generic rules of ``relations.lp``.

:func:`choose` resolves ambiguous stated relations (:class:`~llm_grop.world.relation.Choice`,
"the knife beside the plate"): clingo picks one option per choice so that everything
holds together, preferring options the LLM's relations agree with.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources

import clingo
from clingo import ast

from llm_grop.world.relation import ASP_NAME, AXES, MEANINGS, Choice, Relation

__all__ = ["ASP_NAME", "ConsistencyReport", "Resolution", "check", "choose",
           "largest_consistent_subset", "minimal_conflict"]

_Parts = list[tuple[str, Sequence[clingo.Symbol]]]


#: Why :func:`choose` picked an option: it agrees with a hint; no other option of its
#: choice holds with the rest; or it is the earliest option that does.
WHY: tuple[str, ...] = ("hint", "forced", "first")


@dataclass(frozen=True)
class ConsistencyReport:
    """Whether relations are consistent together.

    ``conflict`` is a minimal conflicting subset in input order: inconsistent, while
    every proper subset is consistent. Empty when ``consistent``.
    """

    consistent: bool
    conflict: tuple[Relation, ...] = ()


def _table_facts() -> str:
    """The relations table as ASP facts: ``axis(R, A, S)`` (on axis ``A`` the subject's
    state is ``S``), ``converse(R, C)`` and ``rests(R, W)``, ``R`` being the ASP constant."""
    out = []
    for m in MEANINGS.values():
        if m.converse is None:  # center: no reference, nothing to say per axis
            continue
        out += [f"axis({m.asp},{axis},{m.state(axis)})." for axis in AXES]
        out.append(f"converse({m.asp},{MEANINGS[m.converse].asp}).")
        if m.rests is not None:
            out.append(f"rests({m.asp},{m.rests}).")
    return "\n".join(out)


@functools.lru_cache(maxsize=1)
def _rules() -> tuple[ast.AST, ...]:
    """The table's facts and the statements of ``relations.lp``, parsed once per process."""
    text = resources.files("llm_grop.arrangement").joinpath("relations.lp").read_text("utf-8")
    statements: list[ast.AST] = []
    ast.parse_string(_table_facts(), statements.append)
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


class _Units:
    """One grounding whose units (lines, or choices) may each be dropped: ``literal[i]``
    is true when unit ``i`` is in; subsets are tried by assumptions."""

    def __init__(self, ctl: clingo.Control, atoms: Sequence[clingo.Symbol]) -> None:
        self.ctl = ctl
        self.literal = [ctl.symbolic_atoms[a].literal for a in atoms]  # type: ignore[union-attr]

    def conflict_core(self, subset: Sequence[int]) -> list[int] | None:
        """``None`` if the units in ``subset`` are consistent, else the units of an unsat core.

        The core's units (in, every other unit out) are inconsistent.
        """
        chosen = set(subset)
        assumptions = [lit if i in chosen else -lit for i, lit in enumerate(self.literal)]
        core: list[int] = []
        result = self.ctl.solve(assumptions=assumptions, on_core=core.extend)
        if result.satisfiable:
            return None
        unit_of = {self.literal[i]: i for i in chosen}
        return sorted(unit_of[lit] for lit in core if lit in unit_of)


def _keep(i: int) -> clingo.Symbol:
    return clingo.Function("keep", [clingo.Number(i)])


def _lines(facts: str, n: int) -> _Units:
    """The ``n`` lines of ``facts`` as units: every line may be dropped."""
    return _Units(_grounded(facts, [("base", []), ("choose", [])]), [_keep(i) for i in range(n)])


def _shrink(lines: _Units, core: list[int]) -> list[int]:
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
    lines = _lines(facts, len(relations))
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


@dataclass(frozen=True)
class Resolution:
    """How :func:`choose` resolved ambiguous relations.

    ``relations``: the picked options' relations, choice by choice (the definite relations
    are not repeated). ``picked``: the option index chosen for each choice. ``why``: per
    choice, one of :data:`WHY`. ``conflict``: non-empty iff no selection is consistent
    (then the others are empty): definite relations and whole choices that cannot hold
    together, in input order (definite first), none of which can be left out (see
    :func:`choose`).
    """

    relations: tuple[Relation, ...]
    picked: tuple[int, ...]
    why: tuple[str, ...]
    conflict: tuple[Relation | Choice, ...] = ()

    @property
    def consistent(self) -> bool:
        """Whether a consistent selection exists."""
        return not self.conflict


def _agrees(option: Sequence[Relation], hints: set[tuple[str, str, str | None]]) -> bool:
    """Whether one of ``option``'s relations is a hint, said either way round."""
    return any(r.key() in hints or (r.reference is not None and r.converse().key() in hints)
               for r in option)


def _picks(model: clingo.Model) -> set[tuple[int, int]]:
    return {(s.arguments[0].number, s.arguments[1].number)
            for s in model.symbols(atoms=True) if s.name == "pick" and len(s.arguments) == 2}


def choose(definite: Sequence[Relation], choices: Sequence[Choice],
           hints: Sequence[Relation] = ()) -> Resolution:
    """One option per choice such that ``definite`` and every picked option hold together.

    Among consistent selections clingo first maximises how many picked options agree with
    ``hints`` (an option agrees when one of its relations is a hint, or a hint's converse;
    hints are the LLM's Template 1 relations), then prefers the earliest options: choice
    0's smallest index, then choice 1's, and so on. ``why[k]`` is ``"hint"`` when the
    picked option agrees with a hint, else ``"forced"`` when no consistent selection
    picks another option of choice ``k``, else ``"first"``.

    With no consistent selection, the conflict is found from an unsat core over the units
    (each definite relation, each whole choice) and shrunk by deletion, as :func:`check`
    does for lines: leaving out any one of its units leaves units that hold together.
    (Smaller subsets hold too, but for the centre convention: leaving out a stacking
    relation can part two objects said to be at the centre.) With no choices, the result
    is :func:`check`'s verdict on ``definite``.
    """
    if not choices:
        return Resolution((), (), (), check(definite).conflict)
    n, k = len(definite), len(choices)
    lines: list[Relation] = list(definite)
    extra = [f"definite({i})." for i in range(n)]
    hinted = {h.key() for h in hints}
    for c, choice in enumerate(choices):
        extra.append(f"choice({c}).")
        for j, option in enumerate(choice.options):
            extra.append(f"option({c},{j}).")
            if _agrees(option, hinted):
                extra.append(f"agrees({c},{j}).")
            for r in option:
                extra.append(f"member({len(lines)},{c},{j}).")
                lines.append(r)
    ctl = _grounded(_facts(lines) + "\n" + "\n".join(extra),
                    [("base", []), ("resolve", []), ("prefer", [clingo.Number(k)])])
    units = _Units(ctl, [_keep(i) for i in range(n)]
                   + [clingo.Function("use", [clingo.Number(c)]) for c in range(k)])
    ctl.configuration.solve.opt_mode = "ignore"  # type: ignore[union-attr]
    core = units.conflict_core(range(n + k))
    if core is not None:
        kept = _shrink(units, core)
        return Resolution((), (), (), tuple(definite[u] if u < n else choices[u - n]
                                            for u in kept))
    everything = list(units.literal)
    # Which options occur in some consistent selection (brave consequences).
    possible: set[tuple[int, int]] = set()
    ctl.configuration.solve.enum_mode = "brave"  # type: ignore[union-attr]
    ctl.configuration.solve.models = 0  # type: ignore[union-attr]
    ctl.solve(assumptions=everything, on_model=lambda m: possible.update(_picks(m)))
    # The preferred selection: the last model of the optimisation is the optimum.
    best: set[tuple[int, int]] = set()
    ctl.configuration.solve.enum_mode = "auto"  # type: ignore[union-attr]
    ctl.configuration.solve.opt_mode = "opt"  # type: ignore[union-attr]

    def on_model(model: clingo.Model) -> None:
        best.clear()
        best.update(_picks(model))

    ctl.solve(assumptions=everything, on_model=on_model)
    picked = tuple(next(j for c2, j in best if c2 == c) for c in range(k))
    why = []
    for c, j in enumerate(picked):
        if _agrees(choices[c].options[j], hinted):
            why.append("hint")
        elif {jj for cc, jj in possible if cc == c} == {j}:
            why.append("forced")
        else:
            why.append("first")
    return Resolution(tuple(r for c, j in enumerate(picked) for r in choices[c].options[j]),
                      picked, tuple(why))
