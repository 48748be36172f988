"""End to end in a real headless Chromium (Debian's, driven by Playwright): upload a real image,
watch it solve, see the annotated frame and zoom it, download the WCS and read it with astropy;
run an analysis over two images; simulate an image and see its error against the truth; cancel
a job from its page.

With ``STARTRACK_WRITE_SCREENSHOTS=1`` the pages are also saved to ``docs/web/*.png`` (the
screenshots of ``docs/web.md``); otherwise nothing is written to the tree.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from astropy.io import fits
from astropy.wcs import WCS

from startrack.frames import angle_between, radec_to_vector
from startrack.units import ARCSEC, DEG

CHROMIUM = Path("/usr/bin/chromium")
pytestmark = pytest.mark.skipif(not CHROMIUM.exists(), reason="Debian's chromium is not installed at "
                                "/usr/bin/chromium (python3 tasks.py test installs it)")
SHOTS = Path(__file__).resolve().parents[2] / "docs" / "web"
WRITE_SHOTS = os.environ.get("STARTRACK_WRITE_SCREENSHOTS") == "1"
JOB_URL = re.compile(r".*/jobs/[0-9a-f]{32}$")
BATCH_URL = re.compile(r".*/batches/[0-9a-f]{32}$")


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        chromium = p.chromium.launch(executable_path=str(CHROMIUM), headless=True, args=[
            "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
            "--disable-sync", "--no-first-run"])
        yield chromium
        chromium.close()


@pytest.fixture()
def page(browser, idle_server):
    context = browser.new_context(base_url=idle_server.url, viewport={"width": 1360, "height": 900},
                                  accept_downloads=True)
    context.set_default_timeout(60_000)
    tab = context.new_page()
    yield tab
    context.close()


def screenshot(page, name: str) -> None:
    if WRITE_SHOTS:
        SHOTS.mkdir(exist_ok=True)
        page.screenshot(path=str(SHOTS / f"{name}.png"), full_page=True)


def wait_for_figure(page) -> None:
    page.wait_for_function("() => { const f = document.getElementById('figure');"
                           " return f && f.complete && f.naturalWidth > 0; }")


def test_upload_a_real_image_watch_it_solve_and_download_its_wcs(page, real_images, truth_table, tmp_path):
    page.goto("/")
    page.set_input_files("#file-input", str(real_images["img3.png"]))
    screenshot(page, "upload")
    page.click("#upload-button")
    page.wait_for_url(JOB_URL)
    page.wait_for_selector("#job-state.state-done")  # the page polls the API and reloads when done
    wait_for_figure(page)
    assert page.locator("li[data-stage].done").count() == 6
    assert "matched" in page.inner_text("#numbers")
    view = page.locator(".zoom-view")
    view.hover()
    page.mouse.wheel(0, -400)
    page.wait_for_function("() => parseFloat(document.querySelector('[data-zoom]').dataset.scale) > 1.2")
    page.mouse.move(700, 400)
    page.mouse.down()
    page.mouse.move(600, 350, steps=5)
    page.mouse.up()
    view.dblclick()
    assert page.get_attribute("[data-zoom]", "data-scale") == "1.000"
    screenshot(page, "job")
    with page.expect_download() as download:
        page.click("#downloads a[download='solution.wcs']")
    path = tmp_path / "solution.wcs"
    download.value.save_as(path)
    header = fits.getheader(path)
    header["NAXIS"], header["NAXIS1"], header["NAXIS2"] = 2, header["IMAGEW"], header["IMAGEH"]
    row = next(r for r in truth_table if r["file"] == "img3.png")
    sky = WCS(header).pixel_to_world((int(row["width"]) - 1) / 2, (int(row["height"]) - 1) / 2)
    truth = radec_to_vector(float(row["ra_center_deg"]) * DEG, float(row["dec_center_deg"]) * DEG)
    error = angle_between(radec_to_vector(sky.ra.rad, sky.dec.rad), truth)
    assert error < 2 * float(row["pixscale_arcsec"]) * ARCSEC


def test_the_guided_checkbox_measures_the_predicted_stars(page, real_images):
    """roof.jpg with "measure the fainter catalog stars where the solution predicts them" ticked:
    the result says how many of its matches were measured so (3: docs/identification.md)."""
    page.goto("/")
    page.set_input_files("#file-input", str(real_images["roof.jpg"]))
    page.check("#upload-form input[name=guided]")
    page.click("#upload-button")
    page.wait_for_url(JOB_URL)
    page.wait_for_selector("#job-state.state-done")
    assert re.search(r"; \d+ of them measured where the solution predicts them", page.inner_text("#guided"))


def test_run_an_analysis_over_two_images(page, real_images):
    page.goto("/")
    page.set_input_files("#file-input", [str(real_images["roof.jpg"]), str(real_images["tree.jpg"])])
    page.fill("#upload-form input[name=name]", "roof and tree")
    page.click("#upload-button")
    page.wait_for_url(BATCH_URL)
    page.wait_for_selector("#analyse-link")  # shown once both jobs have finished
    assert page.locator("#batch-jobs .state-done").count() == 2
    screenshot(page, "batch")
    page.click("#analyse-link")
    page.select_option("#analysis-select", "radial")
    assert page.locator(".analysis-params.shown").count() == 1
    screenshot(page, "analyses")
    page.click("#analysis-button")
    page.wait_for_url(JOB_URL)
    page.wait_for_selector("#job-state.state-done")
    wait_for_figure(page)
    assert "roof and tree" in page.inner_text("#summary")
    assert page.locator("#downloads a[download='radial_stars.csv']").count() == 1
    screenshot(page, "analysis")


def test_a_simulated_image_shows_its_error_against_the_truth(page):
    page.goto("/")
    page.fill("input[name=sim_width]", "640")
    page.fill("input[name=sim_height]", "480")
    page.fill("input[name=sim_seed]", "11")
    page.click("#simulate-button")
    page.wait_for_url(JOB_URL)
    page.wait_for_selector("#job-state.state-done")
    wait_for_figure(page)
    text = page.inner_text("#truth-error")
    assert re.match(r"[\d.]+″ total \([\d.]+ px\)", text)
    assert float(re.search(r"\(([\d.]+) px\)", text).group(1)) < 0.5
    screenshot(page, "simulated")


def test_cancel_a_job_from_its_page(page, random_field):
    page.goto("/")
    page.set_input_files("#file-input", str(random_field))
    page.check("#upload-form input[name=fov_mode][value=fov]")
    page.fill("#upload-form input[name=fov_deg]", "10")
    page.select_option("#upload-form select[name=method]", "pyramid")
    page.click("#upload-button")
    page.wait_for_url(JOB_URL)
    page.wait_for_selector("li[data-stage='identify'].current")  # live stage progress, from the worker
    assert page.inner_text("#job-state") == "running"
    page.click("#cancel-button")
    page.wait_for_selector("#job-state.state-cancelled")
    assert page.locator("#cancel-button").count() == 0
