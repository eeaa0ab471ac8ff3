"""Helpers shared by the command-line tests."""

from __future__ import annotations

REQUEST = "set the table with a dinner plate, a dinner fork and a dinner knife"


def openai_flags(server) -> list[str]:  # type: ignore[no-untyped-def]
    """Flags pointing the ``openai`` backend at the local chat server, without retries."""
    return ["--llm", "openai", "--base-url", server.url, "--retries", "0"]


def one_line_error(capsys) -> str:  # type: ignore[no-untyped-def]
    """The one non-empty line the command printed on stderr (and no traceback)."""
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    return lines[0]
