"""Headless Debian chromium driven by selenium, for the tests marked ``browser``: the system's
chromium and chromedriver (no browser download), with the flags that work on a closed network.
``missing()`` says why such a test must skip (None when all is there); ``browser`` is the fixture
(import it into the test module)."""
import importlib.util
import os
import shutil

import pytest

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-dev-shm-usage", "--window-size=1400,1000"]


def missing():
    if not os.path.exists(CHROMIUM):
        return f"needs Debian's chromium at {CHROMIUM} (apt-get install chromium chromium-driver)"
    if not os.path.exists(CHROMEDRIVER):
        return f"needs chromium-driver at {CHROMEDRIVER} (apt-get install chromium-driver)"
    if importlib.util.find_spec("selenium") is None:
        return "needs selenium (pip install -e '.[test]')"
    return None


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


def console_errors(driver):
    """The browser console's errors (level SEVERE) since the last call."""
    return [entry for entry in driver.get_log("browser") if entry["level"] == "SEVERE"]
