"""The service tests' shared server: one ``llm-grop serve`` per module."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from browser_support import browser, screenshots  # noqa: F401 - fixtures for the browser test
from service_support import Server, start_server


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = start_server(tmp_path_factory.mktemp("serve") / "jobs.sqlite")
    yield s
    s.stop()
