"""One docs build per rig variant per session, and one headless Chromium (selenium + Debian's chromedriver).

Selenium rather than raw DevTools: its WebDriver calls (get, find elements, execute_script,
save_screenshot) wait for the page load and read images and links without hand-rolled websocket
plumbing; the Debian chromedriver matches the Debian chromium, so no driver is downloaded.
"""
from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import pytest

from tests.bom.conftest import CHANGES, build_py

CHROMIUM, CHROMEDRIVER = "/usr/bin/chromium", "/usr/bin/chromedriver"


@pytest.fixture(scope="session")
def docs_default(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("docs") / "default"
    r = build_py("docs", "--out", str(out), "-q")
    assert r.returncode == 0, r.stderr
    return out


@pytest.fixture(scope="session")
def docs_changed(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("docs") / "changed"
    r = build_py("docs", "--out", str(out), "-q", *CHANGES)
    assert r.returncode == 0, r.stderr
    return out


@pytest.fixture(scope="session")
def browser():
    if not (Path(CHROMIUM).exists() and Path(CHROMEDRIVER).exists()):
        pytest.skip("Debian's chromium and chromium-driver are not installed")
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.webdriver.chrome.service import Service
    profile = tempfile.mkdtemp(prefix="chromium-profile-")
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--disable-dev-shm-usage", f"--user-data-dir={profile}", "--window-size=1280,1400"):
        opts.add_argument(flag)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    driver.set_page_load_timeout(60)
    yield driver
    driver.quit()
    shutil.rmtree(profile, ignore_errors=True)
