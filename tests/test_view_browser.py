"""The live view in a real browser: headless Debian chromium driven by selenium (the system's
chromium and chromedriver; no browser download), on a paced replay of a recording from
recordings/ under load and on the `sim` source.

Marked ``browser`` (not in the default run: ``pytest -m browser``; CI runs them in a stage of its
own that installs chromium and chromium-driver). They skip with the reason when chromium, its
driver or selenium is missing. ``GYROFILTER_LIVE_SCREENSHOT=docs/figures/live_view.png pytest -m
browser`` also writes the README's screenshot (no assertion is made on its pixels).
"""
import json
import os
import signal
import time

import numpy as np
import pytest

from gyrofilter.cli import main
from gyrofilter.recording import read_recording
from support import REPO
from support.browser import browser, console_errors, missing  # noqa: F401 (browser: the fixture)
from support.live import EventReader, StalledClient, start_run, status, wait_for

# still, a 90-degree turn about x at 15-22 s, still; relative to the repository, where the run starts
ROTATION = "recordings/mpu6050_rotate_x90_100s.csv.gz"
IDS = ("plot-x", "plot-y", "plot-z", "rows-out", "samples-in", "lost-samples", "calibration")

pytestmark = [pytest.mark.browser, pytest.mark.skipif(missing() is not None, reason=str(missing()))]


def rows_out(driver):
    text = driver.find_element("id", "rows-out").text
    assert text.isdigit(), text
    return int(text)


def check_page(driver, port):
    """Open the view; its elements are there, rows-out grows, the console has no error."""
    driver.get(f"http://127.0.0.1:{port}/")
    assert driver.title == "gyrofilter live view"
    for element in IDS:
        assert driver.find_element("id", element).is_displayed()
    assert {driver.find_element("id", f"plot-{a}").tag_name for a in "xyz"} == {"canvas"}
    wait_for(lambda: rows_out(driver) > 0, what="rows-out above 0")
    first = rows_out(driver)
    wait_for(lambda: rows_out(driver) > first, what="rows-out to grow")
    assert driver.find_element("id", "samples-in").text.isdigit()
    assert driver.find_element("id", "lost-samples").text == "0"
    wait_for(lambda: driver.find_element("id", "calibration").text == "calibrated", what="the calibration")
    assert driver.find_element("id", "connection").text == "live"


def check_labels(driver):
    """Issue 38: the Allan plot's "1e-3" overlapped its "1e-2 s", "1e1" was clipped, no axis had a
    unit and tick labels mixed precisions (0.100 / 0.0500 / 0). Every text each figure draws is
    listed by the page (canvas.dataset.labels, CSS px): inside its canvas, overlapping none of the
    others, a title with its unit on both axes, and the tick labels of one axis with one number of
    decimals. The Allan table's columns name their units."""
    for canvas in ("plot-x", "plot-y", "plot-z", "plot-allan"):
        element = driver.find_element("id", canvas)
        boxes = json.loads(element.get_attribute("data-labels") or "[]")
        w, h = (driver.execute_script(f"return arguments[0].{side};", element) for side in ("clientWidth", "clientHeight"))
        assert boxes, canvas
        for i, b in enumerate(boxes):
            assert 0 <= b["x0"] < b["x1"] <= w and 0 <= b["y0"] < b["y1"] <= h, (canvas, b, w, h)
            for other in boxes[:i]:
                apart = b["x1"] <= other["x0"] or other["x1"] <= b["x0"] or b["y1"] <= other["y0"] or other["y1"] <= b["y0"]
                assert apart, (canvas, b, other)
        titles = {b["kind"]: b["text"] for b in boxes if b["kind"].endswith("title")}
        assert titles["y-title"].endswith("(deg/s)") and titles["x-title"].endswith("(s)"), (canvas, titles)
        if canvas != "plot-allan":
            ticks = [b["text"] for b in boxes if b["kind"] == "tick" and b["y0"] < h - 35]  # the rate axis
            assert len({len(t.partition(".")[2]) for t in ticks}) == 1, (canvas, ticks)
    heads = [th.text for th in driver.find_elements("css selector", ".allan-table th")]
    assert heads[:4] == ["τ (s)", "x (deg/s)", "y (deg/s)", "z (deg/s)"], heads


def test_a_paced_replay_under_load(browser, tmp_path, capsys):
    """12 stream clients, 3 of which never read, and the browser: the run still writes the rows
    `replay --out` writes for the same file."""
    out = tmp_path / "run.csv"
    proc, port = start_run("--source", f"replay:{ROTATION},realtime,speed=5", "--out", str(out))
    try:
        readers = [EventReader(port) for _ in range(9)]
        for r in readers:
            r.start()
        stalled = [StalledClient(port) for _ in range(3)]
        check_page(browser, port)
        assert status(port)["clients"] == 13
        browser.find_element("css selector", "#window option[value='60']").click()
        wait_for(lambda: (status(port)["t_s"] or 0) > 45, what="45 s of the recording")
        wait_for(lambda: len(browser.find_elements("css selector", "#allan tr")) > 3, what="the Allan table")
        shot = os.environ.get("GYROFILTER_LIVE_SCREENSHOT")
        if shot:
            browser.save_screenshot(shot)
        check_labels(browser)
        browser.set_window_size(820, 900)  # narrow: the labels must still fit and stay apart
        time.sleep(0.5)  # the page redraws every 0.1 s after a resize
        check_labels(browser)
        assert console_errors(browser) == []
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 0, err
    assert browser.find_element("id", "connection").text == "run ended"
    assert console_errors(browser) == []
    replayed = tmp_path / "replayed.csv"
    assert main(["replay", str(REPO / ROTATION), "--out", str(replayed)]) == 0
    capsys.readouterr()
    got, want = read_recording(out), read_recording(replayed)
    assert len(got) == len(want) == (len(read_recording(REPO / ROTATION)) - 200) // 5
    np.testing.assert_array_equal(got.t_s, want.t_s)
    np.testing.assert_array_equal(got.gyro_dps, want.gyro_dps)
    assert rows_out(browser) == len(want)
    for client in stalled:
        client.close()


def test_the_sim_source(browser):
    proc, port = start_run("--source", "sim:seed=3", "--duration", "600")
    try:
        check_page(browser, port)
        assert console_errors(browser) == []
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 0, err
    assert "stopped by SIGINT" in err
