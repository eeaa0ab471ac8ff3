"""``llm-grop serve`` refuses an unsafe or broken configuration at start, with one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from llm_grop.cli import main
from service_support import RECORDING


@pytest.mark.parametrize(("args", "words"), [
    (["--host", "0.0.0.0"], "--host 0.0.0.0: not a loopback address; serving other hosts "
                            "needs --token"),
    (["--host", "192.168.1.5", "--token", "short"], "--token: 5 characters; use at least 16"),
    (["--llm", "replay"], "--llm replay: needs --replay FILE"),
    (["--llm", "replay", "--replay", "missing.jsonl"], "--replay missing.jsonl: no such file"),
    (["--llm", "nope"], "--llm: unknown"),
])
def test_a_bad_configuration_is_refused_at_start(args: list[str], words: str,
                                                tmp_path: Path, capsys) -> None:
    assert main(["serve", "--db", str(tmp_path / "jobs.sqlite"), *args]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and "Traceback" not in err


def test_loopback_names_need_no_token() -> None:
    from llm_grop.service.config import check_bind

    for host in ("127.0.0.1", "localhost", "::1", "127.0.0.2"):
        check_bind(host, None)


def test_a_foreign_database_is_refused(tmp_path: Path, capsys) -> None:
    db = tmp_path / "jobs.sqlite"
    db.write_text("not a database at all, just text that is long enough" * 40)
    assert main(["serve", "--db", str(db), "--llm", "replay", "--replay",
                 str(RECORDING)]) == 2
    assert "not an llm-grop service database" in capsys.readouterr().err
