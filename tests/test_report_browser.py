"""The HTML report in a real browser (headless Chromium through selenium).

Outside CI the test skips, with the reason, when Chromium or chromedriver is
missing; with CI=true a missing browser fails the run.  A screenshot is kept
in test-artifacts/ugv-report.png.
"""

import os
import shutil
import tempfile
from pathlib import Path

import pytest

from ssecert.certify import certify
from ssecert.examples import load_example
from ssecert.report.html import write_report

ARTIFACTS = Path(__file__).resolve().parents[1] / "test-artifacts"
CHROMIUM = (
    shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
)
CHROMEDRIVER = shutil.which("chromedriver")


def _browser():
    missing = [
        name
        for name, path in (("chromium", CHROMIUM), ("chromedriver", CHROMEDRIVER))
        if path is None
    ]
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        missing.append("selenium")
    if missing:
        reason = (
            f"no headless browser: {', '.join(missing)} not installed (Debian packages "
            f"chromium and chromium-driver, Python package selenium)"
        )
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(reason)
        pytest.skip(reason)
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in (
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--disable-dev-shm-usage",
        "--window-size=1280,2400",
        f"--user-data-dir={tempfile.mkdtemp(prefix='ssecert-chromium-')}",
    ):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service(executable_path=CHROMEDRIVER), options=options)


@pytest.fixture(scope="module")
def ugv_page(tmp_path_factory):
    result = certify(load_example("ugv"), runs=12)
    path = tmp_path_factory.mktemp("report") / "ugv.html"
    write_report(result, path)
    driver = _browser()
    try:
        driver.get(path.as_uri())
        yield driver
    finally:
        driver.quit()


@pytest.mark.slow
def test_report_renders_without_console_errors(ugv_page):
    from selenium.webdriver.common.by import By

    logs = ugv_page.get_log("browser")
    errors = [entry for entry in logs if entry["level"] == "SEVERE"]
    assert not errors, errors
    ARTIFACTS.mkdir(exist_ok=True)
    body = ugv_page.find_element(By.TAG_NAME, "body")
    height = ugv_page.execute_script("return document.body.scrollHeight")
    ugv_page.set_window_size(1280, min(int(height) + 100, 12000))
    assert body.screenshot(str(ARTIFACTS / "ugv-report.png"))
    assert (ARTIFACTS / "ugv-report.png").stat().st_size > 10_000


def test_overall_verdict_and_summary_are_visible(ugv_page):
    from selenium.webdriver.common.by import By

    overall = ugv_page.find_element(By.ID, "overall-verdict")
    assert overall.is_displayed() and "fails" in overall.text
    badge = ugv_page.find_element(By.CSS_SELECTOR, "#overall .badge")
    assert badge.is_displayed() and badge.text == "fails"
    rows = ugv_page.find_elements(By.CSS_SELECTOR, "#summary tbody tr")
    ids = [r.find_element(By.TAG_NAME, "a").text for r in rows]
    assert {"observability", "sparse_observability", "observer_gain", "observer_stability"} <= set(
        ids
    )
    verdicts = {
        r.find_element(By.TAG_NAME, "a").text: r.find_element(By.CSS_SELECTOR, ".badge").text
        for r in rows
    }
    assert verdicts["sparse_observability"] == "fails"
    assert verdicts["observability"] == "holds"


def test_breaking_sensor_and_the_reason_are_shown(ugv_page):
    from selenium.webdriver.common.by import By

    why = ugv_page.find_element(By.ID, "why-not-correctable")
    assert why.is_displayed()
    assert "cannot be corrected" in why.text and "position" in why.text
    breaking = ugv_page.find_elements(By.CSS_SELECTOR, "#sensors li.breaking")
    assert [b.text.split(" (")[0] for b in breaking] == ["position"]
    assert ugv_page.find_element(By.CSS_SELECTOR, "#sensors svg").is_displayed()


def test_stealthy_plot_has_two_trajectories_and_one_output(ugv_page):
    from selenium.webdriver.common.by import By

    plot = ugv_page.find_element(By.ID, "stealthy-plot")
    assert plot.is_displayed()
    assert len(plot.find_elements(By.CSS_SELECTOR, "#stealthy-trajectory-a")) == 1
    assert len(plot.find_elements(By.CSS_SELECTOR, "#stealthy-trajectory-b")) == 1
    assert len(plot.find_elements(By.CSS_SELECTOR, "[id^='stealthy-output']")) == 1
    for gid in ("stealthy-trajectory-a", "stealthy-trajectory-b", "stealthy-output"):
        size = plot.find_element(By.ID, gid).size
        assert size["width"] > 50 and size["height"] > 10


def test_simulation_plots_are_visible(ugv_page):
    from selenium.webdriver.common.by import By

    plots = ugv_page.find_elements(By.CSS_SELECTOR, "#simulations figure.sim-plot")
    assert len(plots) >= 2
    for fig in plots:
        assert fig.is_displayed()
        assert fig.find_elements(By.CSS_SELECTOR, "[id$='-error-mean']")
        assert fig.find_elements(By.CSS_SELECTOR, "[id$='-support-mean']")
    assert ugv_page.find_element(By.ID, "region-plot").is_displayed()
