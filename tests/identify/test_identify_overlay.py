"""Star overlay from a prior attitude (Fowler 2013 Ch. 6)."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera, Status
from startrack.camera import get_preset
from startrack.catalog import load_catalog
from startrack.errors import InvalidInputError
from startrack.frames import angle_between, attitude_error, boresight, random_rotations
from startrack.identify._overlay import OverlayOptions, catalog_star_set, match_overlay
from startrack.units import ARCSEC, DEG

CAMERA = Camera.from_fov(1024, 1024, 12.0)
STARS = catalog_star_set(7.0)


def _star_list(seed, camera=CAMERA, stars=STARS, max_stars=40, sigma_px=0.3):
    """Brightest-first catalog stars in the field of a random attitude with centroid noise, the
    brightest one missing and a false star second brightest; truth, x, y and HIP (-1: false)."""
    rng = np.random.default_rng(seed)
    truth = random_rotations(rng=rng)
    cam_vec = truth.apply(stars.vectors)
    idx = np.flatnonzero(cam_vec[:, 2] > math.cos(math.radians(camera.fov_diagonal_deg) / 2 + 0.01))
    x, y = camera.vector_to_pixel(cam_vec[idx])  # stars.vectors are brightest first
    inside = camera.in_image(x, y, margin_px=2.0)
    idx, x, y = idx[inside], x[inside], y[inside]
    gap = np.hypot(x[:, None] - x[None], y[:, None] - y[None]) + 1e9 * np.eye(x.size)
    single = gap.min(axis=1) > 5.0  # a double closer than 5 px is one spot to a detector
    idx, x, y = idx[single][1:max_stars], x[single][1:max_stars], y[single][1:max_stars]
    x, y = x + rng.normal(0, sigma_px, x.size), y + rng.normal(0, sigma_px, y.size)
    hip = load_catalog().hip[stars.catalog_rows[idx]].astype(np.int64)
    x = np.insert(x, 1, rng.uniform(0, camera.width - 1))
    y = np.insert(y, 1, rng.uniform(0, camera.height - 1))
    return truth, x, y, np.insert(hip, 1, -1)


def _off(rot, angle_deg, rng):
    """``rot`` turned by ``angle_deg`` about a random axis."""
    axis = rng.normal(size=3)
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle_deg * DEG) * rot


def _check(outcome, truth, hip, camera=CAMERA):
    assert outcome.status is Status.OK, outcome.reason
    cand = outcome.candidate
    assert cand.image_index.size >= 10
    assert 1 not in cand.image_index  # the false star stays unmatched ("noise")
    np.testing.assert_array_equal(load_catalog().hip[cand.catalog_rows], hip[cand.image_index])
    pixel = camera.pixel_scale_arcsec * ARCSEC
    assert attitude_error(truth, cand.rot_cam_from_icrs) < 2 * pixel  # roll is the weak axis
    assert angle_between(boresight(truth), boresight(cand.rot_cam_from_icrs)) < 0.3 * pixel


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_identifies_with_a_prior_two_to_three_degrees_off(seed):
    truth, x, y, hip = _star_list(seed)
    prior = _off(truth, 2.0 + 0.5 * seed / 3 * 2, np.random.default_rng(seed))
    outcome = match_overlay(x, y, CAMERA, STARS, prior, prior_sigma_deg=1.0)
    _check(outcome, truth, hip)
    assert outcome.n_trials > 1  # found by the search, not the direct overlay


def test_confirms_a_good_attitude_with_the_direct_overlay():
    truth, x, y, hip = _star_list(4)
    outcome = match_overlay(x, y, CAMERA, STARS, _off(truth, 0.01, np.random.default_rng(4)), prior_sigma_deg=0.02)
    _check(outcome, truth, hip)
    assert outcome.n_trials == 1


def test_wide_distorted_camera_of_seed_003():
    camera = get_preset("aptina-mt9p031")  # 50 deg field, radial distortion; Fowler 2013 overlays to V 4
    stars = catalog_star_set(4.0)
    truth, x, y, hip = _star_list(5, camera, stars)
    outcome = match_overlay(x, y, camera, stars, _off(truth, 3.0, np.random.default_rng(5)), prior_sigma_deg=1.5)
    _check(outcome, truth, hip, camera)


def test_refuses_a_prior_that_is_far_off_and_random_stars():
    truth, x, y, _ = _star_list(6)
    far = match_overlay(x, y, CAMERA, STARS, _off(truth, 30.0, np.random.default_rng(6)), prior_sigma_deg=1.5)
    assert far.status is Status.NO_MATCH and far.candidate is None
    rng = np.random.default_rng(7)
    fake = match_overlay(rng.uniform(0, 1023, 30), rng.uniform(0, 1023, 30), CAMERA, STARS, truth,
                         prior_sigma_deg=1.5)
    assert fake.status is Status.NO_MATCH
    assert match_overlay(x[:2], y[:2], CAMERA, STARS, truth, prior_sigma_deg=1.0).status is Status.TOO_FEW_STARS


def test_invalid_input_raises():
    with pytest.raises(InvalidInputError, match="prior_sigma_deg"):
        match_overlay([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], CAMERA, STARS, Rotation.identity(), prior_sigma_deg=45.0)
    with pytest.raises(InvalidInputError, match="search_sigmas"):
        OverlayOptions(search_sigmas=0.0)
