"""Terminal summaries of results, with rich."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

from rich.console import Console
from rich.table import Table as RichTable
from rich.text import Text

from llm_grop.arrangement.pipeline import ArrangementResult
from llm_grop.cli.flags import cli_words
from llm_grop.world.failure import Revision
from llm_grop.world.llmlog import LLMSummary
from llm_grop.world.plan import ExecutedStep, RunResult

if TYPE_CHECKING:
    from llm_grop.evaluation.rater import Rating

#: The longest warning line printed, in characters; a longer warning is cut with "…" (the
#: JSON keeps it whole).
WARNING_CHARS = 200


def one_line(text: str, limit: int = WARNING_CHARS) -> str:
    """``text`` on one line (runs of white space, newlines too, become one space), cut to
    ``limit`` characters with a trailing "…"."""
    flat = " ".join(text.split())
    return flat if len(flat) <= limit else flat[:limit - 1].rstrip() + "…"


def print_warnings(warnings: Iterable[str], console: Console, where: str = "") -> None:
    """Each warning as one line ``warning: [where: ]text`` on ``console`` (stderr), cut
    to :data:`WARNING_CHARS` characters; never rich markup, never wrapped."""
    for w in warnings:
        line = Text("warning:", style="yellow")
        line.append(" " + one_line(f"{where}: {cli_words(w)}" if where else cli_words(w)))
        console.print(line, soft_wrap=True, highlight=False)


def print_arrangement(result: ArrangementResult, console: Console,
                      err: Console | None = None) -> None:
    """Relations, conflicts found and resolved, warnings and positions of ``result``.

    Warnings go to ``err`` (stderr), else to ``console``, one line each.
    """
    a = result.arrangement
    # The request is the user's text: never rich markup.
    console.print(Text.assemble(("Request:", "bold"), f" {a.request}"))
    if a.read_by is not None and any(source != "task" for _, source, _ in a.origins):
        who = "the catalog matcher alone" if a.read_by == "catalog" or a.llm is None else \
            f"the LLM ({a.llm.backend} / {a.llm.model})"
        chosen = list(dict.fromkeys(n.rsplit(" ", 1)[0] if n[-1:].isdigit() else n
                                    for n, source, _ in a.origins if source == "llm"))
        console.print(Text.assemble(("Read by:", "bold"), f" {who}" + (
            f"; it chose {', '.join(chosen)}" if chosen else "")))
    size = (f"round, {a.table.width:g} m across" if a.table.is_round
            else f"{a.table.width:g} x {a.table.depth:g} m")
    seats = f", {len(a.table.diners)} diners" if len(a.table.diners) > 1 else ""
    console.print(f"[bold]Table:[/bold] {size}{seats}")
    for k, attempt in enumerate(result.attempts, 1):
        if attempt.conflict:
            lines = "; ".join(r.line or r.sentence() for r in attempt.conflict)
            console.print(f"[yellow]Attempt {k}: conflict found by clingo:[/yellow] {lines}")
        elif not attempt.relations:
            console.print(f"[yellow]Attempt {k}: no usable relation in the answer[/yellow]")
        else:
            console.print(f"[green]Attempt {k}: consistent[/green]")
    print_revisions(a.revisions, console)
    if result.dropped:
        console.print("[yellow]Kept the largest consistent subset; dropped:[/yellow]")
        for r in result.dropped:
            console.print(f"  - {r.line or r.sentence()}")

    rel_table = RichTable(title="Symbolic relations", title_justify="left")
    rel_table.add_column("subject")
    rel_table.add_column("relation")
    rel_table.add_column("reference")
    rel_table.add_column("gap (cm)", justify="right")
    rel_table.add_column("from")
    for r in a.relations:
        gap = result.gaps_m.get(r.key())
        rel_table.add_row(r.subject, r.relation, r.reference or "table",
                          "" if gap is None else f"{gap * 100:.1f}",
                          r.source if r.revision is None else f"revision {r.revision}")
    console.print(rel_table)

    # A line of its own: a table's title wraps at the table's width, which is narrow.
    console.print(f"Positions (m), configuration 0 of {len(result.configurations)} (from 0)",
                  highlight=False)
    pos_table = RichTable()
    for col in ("object", "x", "y", "yaw", "on"):
        pos_table.add_column(col, justify="right" if col in ("x", "y", "yaw") else "left")
    for p in a.placements:
        pos_table.add_row(p.name, f"{p.x:+.3f}", f"{p.y:+.3f}", f"{p.yaw:.2f}", p.on or "table")
    console.print(pos_table)
    print_warnings(a.warnings, err or console)
    if a.llm is not None:
        print_llm(a.llm, console, err)


def print_revisions(revisions: Sequence[Revision], console: Console) -> None:
    """One line per round of the feedback loop: the failure told to the LLM and what came
    of its revision (the failure's and the LLM's words are never rich markup)."""
    for r in revisions:
        head = f"Revision {r.round} ({r.failure.kind}): "
        if r.outcome == "accepted":
            said = "; ".join(x.sentence() for x in r.added) or "the same relations"
            console.print(Text.assemble((head, "green"), f"accepted, {len(r.added)} relation(s) "
                                        f"added, {len(r.removed)} dropped: {said}"))
        else:
            console.print(Text.assemble((head, "yellow"), f"refused ({r.note})"))
        console.print(Text(f"  told: {r.failure.reason}"))


def print_run(result: RunResult, console: Console, err: Console | None = None) -> None:
    """The episode's outcome: success, times, the plan and each object's actions, and the
    planned arrangement's warnings on ``err`` (stderr), else on ``console``."""
    ex, plan = result.execution, result.plan
    console.print(Text.assemble(("Request:", "bold"), f" {result.request}"))
    console.print(f"[bold]Method:[/bold] {result.method}   [bold]seed:[/bold] {result.seed}   "
                  f"[bold]chairs sensed:[/bold] {len(result.scene.chairs)}")
    print_revisions(result.planned.revisions, console)
    # Numbered from 0, as the JSON's configuration_index: one number in both places.
    console.print(f"Plan: configuration {plan.configuration_index} of "
                  f"{plan.configurations_considered} (from 0); expected utility "
                  f"{plan.utility:.1f}, feasibility {plan.feasibility:.2f}, cost "
                  f"{plan.cost_s:.1f} s")
    table = RichTable(title="Execution", title_justify="left")
    for col in ("#", "object", "standing (x, y, θ)", "navigate", "pick", "place", "placed"):
        table.add_column(col)
    reasons = dict(ex.unplaced_reasons)
    for k, name in enumerate(plan.order, 1):
        steps = [s for s in ex.steps if s.object == name]
        place = [s for s in steps if s.action == "place"]
        stand = place[-1].standing if place else None
        table.add_row(
            str(k), name,
            f"{stand.x:.2f}, {stand.y:.2f}, {stand.theta:+.2f}" if stand else "-",
            *(_attempts([s for s in steps if s.action == a]) for a in ("navigate", "pick",
                                                                       "place")),
            "[green]yes[/green]" if name not in ex.unplaced
            else f"[red]no ({reasons.get(name, '?').replace('_', ' ')})[/red]")
    console.print(table)
    verdict = "[green]success[/green]" if ex.success else \
        f"[red]failed[/red] ({', '.join(ex.unplaced)} not placed)"
    rating = final_rating(result)
    console.print(f"Result: {verdict}, rated {rating.score}/5; execution time "
                  f"{ex.execution_time_s:.1f} s (simulated); planning "
                  f"{result.planning_time_s * 1000:.0f} ms; failed attempts {ex.failures}")
    console.print(f"Rated by the automatic rater (`llm-grop rate` explains): {rating.summary}")
    print_warnings(result.planned.warnings, err or console)
    if result.planned.llm is not None:
        print_llm(result.planned.llm, console, err)


def final_rating(result: RunResult) -> Rating:
    """The automatic rater's 1-5 rating of the table the episode left (paper Table III),
    against the objects that were planned."""
    from llm_grop.contract.serialize import arrangement_doc
    from llm_grop.evaluation.rater import rate

    return rate(arrangement_doc(result.final, physical=True),
                requested=[p.name for p in result.planned.placements])


def print_llm(llm: LLMSummary, console: Console, err: Console | None = None) -> None:
    """The LLM's line, and on ``err`` (else ``console``) a note when ``--llm auto`` fell
    back to the small embedded model and it answered (no note when the preferences or the
    examples left it nothing to answer)."""
    from llm_grop.llm.auto import fallback_note
    from llm_grop.llm.embedded import DEFAULT_MODEL

    fell_back = llm.backend == "embedded" and llm.model == DEFAULT_MODEL \
        and llm.chosen_by is not None and bool(llm.calls)
    console.print(llm_line(llm, noted=fell_back))
    if fell_back:
        (err or console).print(f"note: {fallback_note(llm.chosen_by)}", markup=False,
                               highlight=False)


def llm_line(llm: LLMSummary, noted: bool = False) -> str:
    """The LLM's one line: backend and model, why ``--llm auto`` chose it (or, when
    ``noted``, that a note below says why), the calls, which of them the cache or a
    recording answered, and the seconds the live ones took."""
    calls = llm.calls
    cached = sum(c.cached for c in calls)
    live = sum(c.latency_s for c in calls if not c.cached)
    chosen = "" if not llm.chosen_by else \
        " (chosen by --llm auto: see the note)" if noted else f" (auto: {llm.chosen_by})"
    head = f"LLM: {llm.backend} / {llm.model}{chosen}, {len(calls)} " \
        f"call{'s' * (len(calls) != 1)}"
    recorded = sum(c.latency_s for c in calls)
    if llm.backend == "replay":
        return f"{head} replayed from a recording (recorded latency {recorded:.1f} s)"
    if cached == len(calls) and calls:
        return (f"{head}, all from the LLM cache (answered at once; {recorded:.1f} s when "
                "first asked)")
    if cached:
        return f"{head} ({cached} from the LLM cache), {live:.1f} s"
    return f"{head}, {live:.1f} s"


def _attempts(steps: list[ExecutedStep]) -> str:
    """``"ok"``, ``"ok after 2 failed attempts (slid, contact)"`` or ``"failed x3 (no
    IK)"``, with the failed attempts' reasons."""
    if not steps:
        return "-"
    failed = [s for s in steps if not s.ok]
    why = ", ".join(dict.fromkeys((s.reason or "refused").replace("_", " ") for s in failed))
    if steps[-1].ok:
        n = len(failed)
        return "ok" if not n else f"ok after {n} failed attempt{'s' * (n > 1)} ({why})"
    return f"[red]failed x{len(failed)} ({why})[/red]"
