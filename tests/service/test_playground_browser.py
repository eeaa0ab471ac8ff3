"""The playground in a real browser: Debian's Chromium driven by Playwright, on a desktop,
on a phone-sized screen and with JavaScript off.

A visitor types a free request and sees its reading, its relations and its picture; the
permalink opens on a phone with nothing sticking out sideways and the phone's picture; with
JavaScript off, Arrange still works; a MuJoCo run shows its render and video. Screenshots
go to ``$LLM_GROP_SCREENSHOTS`` (``docs/serve/`` is made so), else to the test's folder.
"""

from __future__ import annotations

import re
from pathlib import Path

from playwright.sync_api import Browser, Page, expect

from browser_support import PHONE, fits
from service_support import Server

DESKTOP = {"width": 1100, "height": 1000}
FREE = "I would like a dinner plate with a dinner fork and a dinner knife"


def loaded(page: Page, selector: str) -> bool:
    """Whether the picture at ``selector`` has loaded."""
    return page.eval_on_selector(selector, "img => img.complete && img.naturalWidth > 0")


def test_arrange_a_free_request_on_a_desktop_a_phone_and_without_javascript(
        server: Server, browser: Browser, screenshots: Path) -> None:
    page = browser.new_context(viewport=DESKTOP).new_page()
    page.goto(server.url)
    page.locator("#request").fill(FREE)
    page.get_by_role("button", name="Arrange").click()
    expect(page).to_have_url(re.compile(r"/a/[A-Za-z0-9_-]+$"))
    expect(page.locator("#reading")).to_contain_text("catalog matcher")
    expect(page.locator("#objects li")).to_have_count(3)
    expect(page.locator("#objects")).to_contain_text("a dinner fork")
    expect(page.locator("#relations tbody tr")).not_to_have_count(0)
    expect(page.locator("#relations")).to_contain_text("llm")
    assert loaded(page, "#table")
    assert page.locator("#request").input_value() == FREE  # ready to edit
    expect(page.locator(".history li")).to_have_count(1)
    page.screenshot(path=screenshots / "arrange_desktop.png", full_page=True)
    permalink = page.url

    phone = browser.new_context(viewport=PHONE, is_mobile=True,
                                device_scale_factor=2).new_page()
    phone.goto(permalink)
    expect(phone.locator("#objects li")).to_have_count(3)
    assert loaded(phone, "#table") and fits(phone)
    assert phone.eval_on_selector("#table", "i => i.currentSrc").endswith(
        "table_phone.png")
    phone.screenshot(path=screenshots / "arrange_phone.png", full_page=True)

    plain = browser.new_context(viewport=PHONE, java_script_enabled=False).new_page()
    plain.goto(f"{server.url}/?request=a%20plate%2C%20a%20fork%20and%20a%20knife")
    assert plain.locator("#request").input_value() == "a plate, a fork and a knife"
    plain.get_by_role("button", name="Arrange").click()
    expect(plain).to_have_url(re.compile(r"/a/[A-Za-z0-9_-]+$"))
    expect(plain.locator("#objects li")).to_have_count(3)
    assert fits(plain)


def test_a_refused_request_shows_one_line(server: Server, browser: Browser) -> None:
    page = browser.new_context(viewport=PHONE).new_page()
    page.goto(server.url)
    page.locator("#request").fill("a dinner plate")
    page.locator("input[name=diners]").fill("12")
    page.get_by_role("button", name="Arrange").click()
    expect(page.locator("#job-error")).to_contain_text("12 diners do not fit")
    assert page.locator("#request").input_value() == "a dinner plate"


def test_a_mujoco_run_shows_its_render_and_video(server: Server, browser: Browser,
                                                 screenshots: Path) -> None:
    page = browser.new_context(viewport=DESKTOP).new_page()
    page.goto(server.url)
    page.locator("#request").fill(FREE)
    page.locator("select[name=simulator]").select_option("mujoco")
    page.get_by_role("button", name="Run").click()
    expect(page).to_have_url(re.compile(r"/r/[A-Za-z0-9_-]+$"))
    # The page follows the run's events and shows the result when it ends.
    expect(page.locator("#render-table")).to_be_visible(timeout=240_000)
    expect(page.locator("#summary")).to_contain_text("in mujoco")
    expect(page.locator("#summary")).to_contain_text(re.compile(r"\d+ failed attempts?,"))
    assert loaded(page, "#render-table") and loaded(page, "#room")
    expect(page.locator("#video")).to_have_attribute("src", re.compile(r"\.mp4$"))
    page.screenshot(path=screenshots / "run_mujoco.png", full_page=True)
