"""The live view in a real browser: headless Debian chromium driven by selenium (the system's
chromium and chromedriver; no browser download), on a paced replay of a recording from
recordings/ under load and on the `sim` source.

Marked ``browser`` (not in the default run: ``pytest -m browser``; CI runs them in a stage of its
own that installs chromium and chromium-driver). They skip with the reason when chromium, its
driver or selenium is missing. ``GYROFILTER_LIVE_SCREENSHOT=docs/figures/live_view.png pytest -m
browser`` also writes the README's screenshot (no assertion is made on its pixels).
"""
import os
import signal

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
