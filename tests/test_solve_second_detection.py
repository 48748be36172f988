"""Real photos that the first detection leaves unsolved, solved from a second one with no hint.

:func:`startrack.solve.solve_image` detects an image again when its point solve matches nothing
(:func:`startrack.solve._second_detection`):

* under partial clouds, with the clutter test off: lit clouds make their tiles' background busy,
  and the test refuses the spots of busy tiles, the stars in clear sky beside a cloud's edge
  with them;
* on a frame of star trails, also with the elongation test off and the weighted centroid: the
  windowed centroider's window, a star's size, settles on a piece of a trail.

Truth: astrometry.net (../shared/realdata/truth.csv), as in test_realdata_solve.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

import startrack.solve
from startrack.detect import StarDetector
from startrack.frames import angle_between, radec_to_vector
from startrack.results import Status
from startrack.solve import solve_image
from startrack.units import ARCSEC, DEG

CLOUD_LIGHT = 120.0
"""The clouds' own light, grey levels (they also dim what is behind them by 80 %)."""


def _clouded(grey: np.ndarray, seed: int, cover: float = 0.4) -> np.ndarray:
    """``grey`` (H, W) under soft-edged clouds over ``cover`` of the frame, with their light and
    its noise (0.4 sqrt(light) grey levels), as 8-bit grey levels."""
    rng = np.random.default_rng(seed)
    h, w = grey.shape
    field = ndimage.gaussian_filter(rng.normal(size=(h, w)), sigma=min(h, w) / 12)
    field = (field - field.mean()) / field.std()
    cloud = np.clip((field - np.quantile(field, 1 - cover)) / 0.5, 0, 1)
    light = CLOUD_LIGHT * cloud + np.sqrt(CLOUD_LIGHT * cloud) * 0.4 * rng.normal(size=(h, w))
    return np.clip(np.rint(grey * (1 - 0.8 * cloud) + light), 0, 255).astype(np.uint8)


@pytest.fixture()
def clouded(truth_table, realdata_dir):
    """img4.png under clouds (seed 4) that leave it unsolved with the clutter test on; and its truth row."""
    row = next(r for r in truth_table if r["file"] == "img4.png")
    grey = np.asarray(Image.open(realdata_dir / row["set"] / row["file"]).convert("L"), dtype=np.float64)
    return _clouded(grey, seed=4), row


def _centre_error_px(solution, row) -> float:
    width, height = int(row["width"]), int(row["height"])
    centre = solution.rot_cam_from_icrs.inv().apply(solution.camera.pixel_to_vector((width - 1) / 2, (height - 1) / 2))
    truth = radec_to_vector(float(row["ra_center_deg"]) * DEG, float(row["dec_center_deg"]) * DEG)
    return float(angle_between(centre, truth) / (float(row["pixscale_arcsec"]) * ARCSEC))


def test_a_clouded_photo_solves_from_the_spots_found_without_the_clutter_test(clouded):
    image, row = clouded
    with_test = StarDetector().detect(image)
    solution = solve_image(image)
    assert solution.solved, solution.reason
    assert _centre_error_px(solution, row) < 2.0  # px
    assert len(solution.detections) >= len(with_test) + startrack.solve.SECOND_DETECTION_MIN_SPOTS


def test_without_the_second_solve_the_clouded_photo_is_not_solved(clouded, monkeypatch):
    """The premise of the test above: with the clutter test on, these clouds leave no match."""
    monkeypatch.setattr(startrack.solve, "SECOND_DETECTION_STATUSES", ())
    assert solve_image(clouded[0]).status is Status.NO_MATCH



TRAIL_PX = 28
"""Length of the star trails of :func:`trailed`, px."""


@pytest.fixture()
def trailed(truth_table, realdata_dir):
    """crappy.jpg (grey) with every star drawn out into a horizontal trail of :data:`TRAIL_PX`
    (a box of that length), and the sky's noise that the box smoothed away added back (seeded);
    and its truth row."""
    row = next(r for r in truth_table if r["file"] == "crappy.jpg")
    grey = np.asarray(Image.open(realdata_dir / row["set"] / row["file"]).convert("L"), dtype=np.float64)
    noise = 1.4826 * float(np.median(np.abs(grey - ndimage.median_filter(grey, 5))))
    trails = ndimage.convolve(grey, np.ones((1, TRAIL_PX)) / TRAIL_PX, mode="nearest")
    lost = np.random.default_rng(0).normal(0.0, noise * np.sqrt(1 - 1 / TRAIL_PX), grey.shape)
    return np.clip(np.rint(trails + lost), 0, 255).astype(np.uint8), row


def test_a_photo_of_star_trails_solves_from_their_weighted_centroids(trailed):
    image, row = trailed
    solution = solve_image(image)
    assert solution.solved, solution.reason
    assert _centre_error_px(solution, row) < 2.0  # px


def test_without_the_second_solve_the_trails_are_not_solved(trailed, monkeypatch):
    monkeypatch.setattr(startrack.solve, "SECOND_DETECTION_STATUSES", ())
    assert solve_image(trailed[0]).status is Status.NO_MATCH
