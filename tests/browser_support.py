"""What the browser tests share: Debian's Chromium, launched by Playwright with no network of
its own, the screen sizes, and where screenshots go."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from playwright.sync_api import Browser, Page, sync_playwright

CHROMIUM = Path("/usr/bin/chromium")
#: Flags for a headless Chromium with no network of its own (no sandbox: CI runs as root).
FLAGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]
DESKTOP = {"width": 1100, "height": 900}
PHONE = {"width": 390, "height": 844}


@pytest.fixture
def screenshots(tmp_path: Path) -> Path:
    """Where screenshots go: ``$LLM_GROP_SCREENSHOTS`` (the README's are made so), else the
    test's own folder."""
    where = Path(os.environ.get("LLM_GROP_SCREENSHOTS") or tmp_path / "screenshots")
    where.mkdir(parents=True, exist_ok=True)
    return where


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    """Debian's Chromium, one per test module."""
    assert CHROMIUM.exists(), "Debian's chromium is missing: run scripts/setup.sh --dev"
    with sync_playwright() as pw:
        launched = pw.chromium.launch(executable_path=str(CHROMIUM), args=FLAGS)
        yield launched
        launched.close()


def fits(page: Page) -> bool:
    """Nothing sticks out sideways: no horizontal scrolling."""
    return page.evaluate("document.documentElement.scrollWidth <= window.innerWidth")
