"""The rating website in a real browser: Debian's Chromium driven by Playwright, with the
keyboard alone, on a desktop and on a phone-sized screen.

A rater joins, reads the guidelines, rates 5 pictures with the keys 1-5, leaves, and comes
back on a phone at picture 6. Screenshots of the guidelines, rating and report pages go to
``$LLM_GROP_SCREENSHOTS`` (the README's are made so), else to the test's own folder.
"""

from __future__ import annotations

import sqlite3
from pathlib import Path

from playwright.sync_api import expect, sync_playwright

from browser_support import CHROMIUM, DESKTOP, FLAGS, PHONE, fits
from llm_grop.cli import main
from ratings_support import load_benchmark


def test_a_rater_rates_with_the_keyboard_leaves_and_comes_back(
        bench_dir: Path, tmp_path: Path, screenshots: Path, capsys) -> None:
    assert CHROMIUM.exists(), "Debian's chromium is missing: run scripts/setup.sh --dev"
    db = tmp_path / "study.db"
    assert main(["ratings", "create", "--bench", str(bench_dir), "--db", str(db)]) == 0
    capsys.readouterr()
    assert main(["ratings", "invite", "--db", str(db), "--count", "1"]) == 0
    code = capsys.readouterr().out.strip()
    load = load_benchmark("ratings_load")
    with load.serving(db) as url, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM), args=FLAGS)
        try:
            desktop = browser.new_context(viewport=DESKTOP)
            page = desktop.new_page()
            page.goto(url)
            expect(page.locator("#code")).to_be_focused()
            page.keyboard.type(code.lower())
            page.keyboard.press("Enter")
            expect(page.locator("h1")).to_have_text("How to rate")
            expect(page.locator("table.guidelines tbody tr")).to_have_count(5)
            page.screenshot(path=str(screenshots / "guidelines.png"), full_page=True)
            expect(page.locator("a.button")).to_be_focused()
            page.keyboard.press("Enter")
            expect(page.locator("#progress")).to_have_text("1 / 16")
            expect(page.locator("#objects")).not_to_be_empty()
            page.screenshot(path=str(screenshots / "rating.png"), full_page=True)
            for k in range(1, 6):
                expect(page.locator("button[name=rating]").first).to_be_enabled()
                page.keyboard.press(str(k))
                expect(page.locator("#progress")).to_have_text(f"{k + 1} / 16")
            assert "/rate" in page.url  # no reload: the API did the work
            desktop.close()  # the rater leaves

            phone = browser.new_context(viewport=PHONE, is_mobile=True, has_touch=True,
                                        device_scale_factor=2)
            page = phone.new_page()
            page.goto(url)
            page.locator("#code").fill(code)
            page.keyboard.press("Enter")
            expect(page.locator("p.progress")).to_have_text("You have rated 5 of 16 pictures.")
            assert fits(page)
            page.screenshot(path=str(screenshots / "guidelines-phone.png"), full_page=True)
            page.goto(url + "rate")
            expect(page.locator("#progress")).to_have_text("6 / 16")
            assert fits(page)
            page.screenshot(path=str(screenshots / "rating-phone.png"), full_page=True)
            page.locator("button[name=rating][value='4']").tap()
            expect(page.locator("#progress")).to_have_text("7 / 16")
            phone.close()

            with sqlite3.connect(db) as conn:
                got = conn.execute("SELECT x.rating FROM ratings x JOIN rater_items ri"
                                   " ON ri.item_id = x.item_id AND ri.rater_id = x.rater_id"
                                   " ORDER BY ri.position").fetchall()
            assert [r[0] for r in got] == [1, 2, 3, 4, 5, 4]

            report = tmp_path / "report"
            assert main(["ratings", "report", "--db", str(db), "--out", str(report)]) == 0
            for name, viewport in (("report", DESKTOP), ("report-phone", PHONE)):
                context = browser.new_context(viewport=viewport)
                page = context.new_page()
                page.goto((report / "report.html").as_uri())
                expect(page.locator("h1")).to_have_text(f"Human ratings: {bench_dir.name}")
                expect(page.locator("img.figure").first).to_be_visible()
                assert fits(page)
                page.screenshot(path=str(screenshots / f"{name}.png"), full_page=True)
                context.close()
        finally:
            browser.close()
