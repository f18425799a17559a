"""The report in a real browser: headless Debian chromium (selenium) opens the file a user attaches,
from the disk, with no server and no network, for every shipped recording: every section and
figure is there, the data block reads, and the console has no error.

Marked ``browser`` (``pytest -m browser``; CI's browser stage); they skip with the reason when
chromium, its driver or selenium is missing. ``GYROFILTER_REPORT_SCREENSHOT=docs/figures/report.png
pytest -m browser -k report`` also writes the README's screenshot (no assertion on its pixels).
"""
import json
import os

import pytest

from gyrofilter.cli import main
from gyrofilter.view.report import DATA_ID
from support import REPO
from support.browser import browser, console_errors, missing  # noqa: F401 (browser: the fixture)

pytestmark = [pytest.mark.browser, pytest.mark.skipif(missing() is not None, reason=str(missing()))]

SECTIONS = ("Recording", "Warnings", "The default filter's effect", "Allan deviation and noise coefficients",
            "What the baseline model misses (gap analysis)")


@pytest.mark.parametrize("name", sorted(p.name[: -len(".csv.gz")] for p in (REPO / "recordings").glob("*.csv.gz")))
def test_chromium_opens_the_report(browser, tmp_path, capsys, monkeypatch, name):
    out = tmp_path / f"{name}.html"
    monkeypatch.chdir(REPO)  # the recording as a user names it: recordings/...
    assert main(["report", f"recordings/{name}.csv.gz", "--out", str(out)]) == 0
    capsys.readouterr()
    browser.set_window_size(1280, 1900)
    browser.get(out.as_uri())
    assert browser.title.startswith("gyrofilter sensor report: ")
    data = json.loads(browser.execute_script(f"return document.getElementById('{DATA_ID}').textContent"))
    # "allan and gap" only where the two disagree (its sentences in the data block)
    assert [h.text for h in browser.find_elements("css selector", "h2")] == \
        list(SECTIONS) + ["allan and gap"] * bool(data.get("allan_and_gap"))
    assert data["recording"]["samples"] > 0
    figures = browser.find_elements("css selector", "svg.figure")
    # three Allan figures where allan ran, three traces where the filter ran (each may refuse a record)
    assert len(figures) == 3 * bool(data["allan"]) + 3 * bool(data["filter"])
    for svg in figures:
        size = svg.size
        assert svg.is_displayed() and size["width"] > 250 and size["height"] > 150
    # the page is no wider than the window (the tables of long coefficients scroll in their box)
    assert browser.execute_script("return document.documentElement.scrollWidth") <= 1280
    # issue 38: a command named in the text ("gap --json" in the footer) broke across two lines
    broken = browser.execute_script("return [...document.querySelectorAll('code')]"
                                    ".filter((c) => c.getClientRects().length > 1).map((c) => c.textContent)")
    assert broken == []
    shot = os.environ.get("GYROFILTER_REPORT_SCREENSHOT")
    if shot and name == "mpu6050_static_655s":
        browser.save_screenshot(shot)
    assert console_errors(browser) == []
