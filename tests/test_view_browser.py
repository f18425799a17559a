"""The live view in a real browser: headless Debian chromium driven by selenium (the system's
chromium and chromedriver; no browser download), on a paced replay of a recording from
recordings/ under load and on the `sim` source.

Marked ``browser`` (not in the default run: ``pytest -m browser``; CI runs them in a stage of its
own that installs chromium and chromium-driver). They skip with the reason when chromium, its
driver or selenium is missing. ``GYROFILTER_LIVE_SCREENSHOT=docs/figures/live_view.png pytest -m
browser`` also writes the README's screenshot (no assertion is made on its pixels).
"""
import importlib.util
import os
import shutil
import signal

import numpy as np
import pytest

from gyrofilter.cli import main
from gyrofilter.recording import read_recording
from support import REPO
from support.live import EventReader, StalledClient, start_run, status, wait_for

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-dev-shm-usage", "--window-size=1400,1000"]
# still, a 90-degree turn about x at 15-22 s, still; relative to the repository, where the run starts
ROTATION = "recordings/mpu6050_rotate_x90_100s.csv.gz"
IDS = ("plot-x", "plot-y", "plot-z", "rows-out", "samples-in", "lost-samples", "calibration")


def _missing():
    if not os.path.exists(CHROMIUM):
        return f"needs Debian's chromium at {CHROMIUM} (apt-get install chromium chromium-driver)"
    if not os.path.exists(CHROMEDRIVER):
        return f"needs chromium-driver at {CHROMEDRIVER} (apt-get install chromium-driver)"
    if importlib.util.find_spec("selenium") is None:
        return "needs selenium (pip install -e '.[test]')"
    return None


pytestmark = [pytest.mark.browser, pytest.mark.skipif(_missing() is not None, reason=str(_missing()))]


@pytest.fixture
def browser(tmp_path):
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    options = Options()
    options.binary_location = CHROMIUM
    for flag in FLAGS + [f"--user-data-dir={tmp_path / 'chromium-profile'}"]:
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    driver.set_page_load_timeout(30)
    yield driver
    driver.quit()
    shutil.rmtree(tmp_path / "chromium-profile", ignore_errors=True)


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


def console_errors(driver):
    return [entry for entry in driver.get_log("browser") if entry["level"] == "SEVERE"]


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
