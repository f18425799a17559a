"""The report in a real browser: headless Debian chromium (selenium) opens the file a user attaches,
from the disk, with no server and no network, for every shipped recording: every section and
figure is there, the data block reads and holds what a shipped recording's report must
(``support.report_page.check_shipped_report``: the only test that makes the slower recordings'
reports, with the defaults a user gets), and the console has no error.

Marked ``browser`` (``pytest -m browser``; CI's browser stage); they skip with the reason when
chromium, its driver or selenium is missing. ``GYROFILTER_REPORT_SCREENSHOT=docs/figures/report.png
pytest -m browser -k report`` also writes the README's screenshot (no assertion on its pixels).
"""
import json
import os

import pytest

from gyrofilter.cli import main
from gyrofilter.sources.simulated import DEFAULT_MODEL_PATH
from gyrofilter.view.report import DATA_ID
from support import REPO
from support.browser import browser, console_errors, missing  # noqa: F401 (browser: the fixture)
from support.report_page import check_shipped_report

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
    check_shipped_report(f"recordings/{name}.csv.gz", data, capsys)  # the page's data block as the command wrote it
    # "allan and gap" only where the two disagree (its sentences in the data block)
    assert [h.text for h in browser.find_elements("css selector", "h2")] == \
        list(SECTIONS) + ["allan and gap"] * bool(data.get("allan_and_gap"))
    assert data["recording"]["samples"] > 0
    figures = browser.find_elements("css selector", "svg.figure")
    # three Allan figures where allan ran (and three of the accelerometer's where the record has one), three
    # traces where the filter ran (each may refuse a record)
    allan_figures = 3 * (1 + bool(data["allan"].get("accelerometer"))) if data["allan"] else 0
    assert len(figures) == allan_figures + 3 * bool(data["filter"])
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


def test_chromium_shows_the_accelerometers_allan_deviation_of_a_six_axis_record(browser, tmp_path, capsys):
    """Issue 39: a simulated six-axis MPU6050 record (the default model): the accelerometer's three Allan
    figures beside the gyro's (the same style: measured, interval, fitted model, each resolved term's line,
    in m/s^2) and its coefficients tables."""
    rec, out = tmp_path / "six.csv.gz", tmp_path / "six.html"
    assert main(["simulate", "--model", str(DEFAULT_MODEL_PATH), "--duration", "600", "--seed", "2",
                 "--out", str(rec)]) == 0
    assert main(["report", str(rec), "--out", str(out)]) == 0
    capsys.readouterr()
    browser.set_window_size(1280, 1900)
    browser.get(out.as_uri())
    data = json.loads(browser.execute_script(f"return document.getElementById('{DATA_ID}').textContent"))
    assert sorted(data["allan"]["accelerometer"]["axes"]) == ["x", "y", "z"]
    figures = browser.find_elements("css selector", "svg.figure")
    assert len(figures) == 3 + 3 + 3  # the filter's traces, the gyro's and the accelerometer's Allan figures
    titles = [svg.get_attribute("aria-label") or svg.text for svg in figures]
    accel = [svg for svg, title in zip(figures, titles) if "accelerometer axis" in title]
    assert len(accel) == 3
    for svg in accel:
        assert svg.is_displayed() and svg.size["width"] > 250 and svg.size["height"] > 150
        assert "Allan deviation (m/s^2)" in svg.text and "measured" in svg.text and "fitted model" in svg.text
    headings = [h.text for h in browser.find_elements("css selector", "h3")]
    assert [h for h in headings if "axis" in h] == [f"axis {a}" for a in "xyz"] + [f"accelerometer axis {a}" for a in "xyz"]
    table = browser.find_elements("css selector", "h3 + div.scroll table")[3].text
    assert "velocity random walk" in table and "m/s^2/sqrt(Hz)" in table and "ug/sqrt(Hz)" in table
    assert browser.execute_script("return document.documentElement.scrollWidth") <= 1280
    assert console_errors(browser) == []
