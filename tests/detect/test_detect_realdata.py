"""The default detector on real sky images against astrometry.net's matched stars.

Images and truth: ``../shared/realdata`` (its README.md). ``truth/<image>.corr`` lists the
image stars astrometry.net matched to Tycho-2, at ``field_x``, ``field_y`` in FITS 1-based
pixels (subtract 1 for ours). A matched star counts as found when one of our brightest 30
detections lies within 2 px of it.

Goal (issue brief): at least 80 % found in every image. Three images reach it. For the other
five the shortfall comes from the truth lists more than from a setting (numbers: matched
stars not detected at all / detected but ranked below 30 / rejected by a filter):

* img6 (4 / 0 / 0): the four are at 3.6-4.7 sigma in our detection image, below the 5-sigma
  threshold that keeps pure-noise frames clean (4.5 sigma finds none of them in the top 30);
* orion_trees (7 / 1 / 1), roof (8 / 2 / 0): astrometry.net matched stars at 0.5-4 sigma of
  our matched filter (its noise estimate from pixel differences ignores the JPEG noise's
  correlation, so it goes deeper, and its solver tolerates the false stars that come with it);
* tree (10 / 3 / 0): stars next to the lit tree, where the local noise is several times the
  sky's, and lit leaves brighter than half of the matched stars;
* pleiades (3 / 8 / 1): real stars brighter than eight matched ones are not in astrometry.net's
  index files, so not in the .corr, yet rightly take places in our top 30.

The three low-signal openstartracker frames must give at least the stars astrometry.net matched
(``n_match`` in ``truth.csv``: 9, 9 and 13) among all our detections. Their own fixed-pattern
map ``median_image.png`` is truncated (a 64 KiB file; only rows 0-48 decode), so the test builds
the seed 000 §4.1 median dark from the three frames themselves: the fields differ, so the median
keeps the hot pixels and drops the stars. With it we find 12 / 12, 11 / 12 and 15 / 16 of the
``.corr`` stars at the default 5 sigma (the misses are at 3.4 and 4.5 sigma).

So each image has a regression floor (what the detector finds now, minus one star for the
JPEGs), and the 80 % goal is kept as a strict xfail where it is not met: it turns into a
failure, asking for the mark to go, the day it passes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from astropy.io import fits
from PIL import Image

from startrack.conventions import from_fits_pixels
from startrack.detect import detect, median_frame, to_single_channel
from startrack.units import PIXEL

TOP_N = 30
MATCH_RADIUS = 2.0 * PIXEL
GOAL = 0.80

# image: (folder, minimum stars found in our top 30, reaches the 80 % goal)
IMAGES = {
    "img3.png": ("UBNanosatLab-openstartracker", 12, True),
    "img4.png": ("UBNanosatLab-openstartracker", 10, True),
    "img6.png": ("UBNanosatLab-openstartracker", 12, False),
    "crappy.jpg": ("smroid-cedar-solve", 10, True),
    "orion_trees.jpg": ("smroid-cedar-solve", 17, False),
    "roof.jpg": ("smroid-cedar-solve", 24, False),
    "tree.jpg": ("smroid-cedar-solve", 11, False),
    "pleiades.jpg": ("smroid-cedar-solve", 17, False),
}


def _found(realdata_dir: Path, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Per matched star: found in our top 30 (bool) and distance to our nearest detection."""
    folder = realdata_dir / IMAGES[name][0]
    with Image.open(folder / name) as img:
        image = np.asarray(img)
    corr = fits.getdata(folder / "truth" / (Path(name).stem + ".corr"))
    x, y = from_fits_pixels(np.asarray(corr["field_x"], float), np.asarray(corr["field_y"], float))
    top = detect(image).take(slice(0, TOP_N))
    distance = np.hypot(x[:, None] - top.x[None], y[:, None] - top.y[None]).min(axis=1)
    return distance < MATCH_RADIUS, distance


@pytest.fixture(scope="module")
def results(realdata_dir) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    return {name: _found(realdata_dir, name) for name in IMAGES}


@pytest.mark.parametrize("name", list(IMAGES))
def test_matched_stars_are_in_our_top_30(results, name):
    found, distance = results[name]
    minimum = IMAGES[name][1]
    assert found.sum() >= minimum, (
        f"{name}: {found.sum()}/{found.size} matched stars in our top {TOP_N} "
        f"(regression floor {minimum})")
    # astrometry.net's positions are good to a few tenths of a pixel on these images
    assert np.median(distance[found]) < 0.7 * PIXEL


@pytest.mark.parametrize("name", [
    pytest.param(name, marks=() if meets else pytest.mark.xfail(
        strict=True, reason="below the 80 % goal, see the module docstring"))
    for name, (_, _, meets) in IMAGES.items()
])
def test_eighty_percent_goal(results, name):
    found, _ = results[name]
    assert found.mean() >= GOAL, f"{name}: {found.sum()}/{found.size} found"


OPENSTARTRACKER = ("img3.png", "img4.png", "img6.png")


@pytest.mark.parametrize("name", OPENSTARTRACKER)
def test_low_signal_frames_give_the_matched_stars(realdata_dir, truth_table, name):
    folder = realdata_dir / "UBNanosatLab-openstartracker"
    frames = {}
    for other in OPENSTARTRACKER:
        with Image.open(folder / other) as img:
            frames[other] = to_single_channel(np.asarray(img))
    dark = median_frame(list(frames.values()))
    corr = fits.getdata(folder / "truth" / (Path(name).stem + ".corr"))
    x, y = from_fits_pixels(np.asarray(corr["field_x"], float), np.asarray(corr["field_y"], float))
    det = detect(frames[name], dark_frame=dark)
    distance = np.hypot(x[:, None] - det.x[None], y[:, None] - det.y[None]).min(axis=1)
    n_match = int(next(row["n_match"] for row in truth_table if row["file"] == name))
    assert (distance < MATCH_RADIUS).sum() >= max(n_match, len(x) - 1)
    assert np.median(distance[distance < MATCH_RADIUS]) < 0.3 * PIXEL
