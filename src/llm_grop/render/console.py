"""Terminal summaries of results, with rich."""

from __future__ import annotations

from rich.console import Console
from rich.table import Table as RichTable

from llm_grop.arrangement.pipeline import ArrangementResult


def print_arrangement(result: ArrangementResult, console: Console) -> None:
    """Relations, conflicts found and resolved, warnings and positions of ``result``."""
    a = result.arrangement
    console.print(f"[bold]Request:[/bold] {a.request}")
    console.print(f"[bold]Table:[/bold] {a.table.width:g} x {a.table.depth:g} m")
    for k, attempt in enumerate(result.attempts, 1):
        if attempt.conflict:
            lines = "; ".join(r.line or r.sentence() for r in attempt.conflict)
            console.print(f"[yellow]Attempt {k}: conflict found by clingo:[/yellow] {lines}")
        elif not attempt.relations:
            console.print(f"[yellow]Attempt {k}: no usable relation in the answer[/yellow]")
        else:
            console.print(f"[green]Attempt {k}: consistent[/green]")
    if result.dropped:
        console.print("[yellow]Kept the largest consistent subset; dropped:[/yellow]")
        for r in result.dropped:
            console.print(f"  - {r.line or r.sentence()}")

    rel_table = RichTable(title="Symbolic relations", title_justify="left")
    rel_table.add_column("subject")
    rel_table.add_column("relation")
    rel_table.add_column("reference")
    rel_table.add_column("gap (cm)", justify="right")
    for r in a.relations:
        gap = result.gaps_m.get(r.key())
        rel_table.add_row(r.subject, r.relation, r.reference or "table",
                          "" if gap is None else f"{gap * 100:.1f}")
    console.print(rel_table)

    pos_table = RichTable(title=f"Positions (m), configuration 1 of "
                          f"{len(result.configurations)}", title_justify="left")
    for col in ("object", "x", "y", "yaw", "on"):
        pos_table.add_column(col, justify="right" if col in ("x", "y", "yaw") else "left")
    for p in a.placements:
        pos_table.add_row(p.name, f"{p.x:+.3f}", f"{p.y:+.3f}", f"{p.yaw:.2f}", p.on or "table")
    console.print(pos_table)
    for w in a.warnings:
        console.print(f"[yellow]warning:[/yellow] {w}")
    if a.llm is not None:
        latency = sum(c.latency_s for c in a.llm.calls)
        console.print(f"LLM: {a.llm.backend} / {a.llm.model}, {len(a.llm.calls)} calls, "
                      f"{latency:.1f} s")
