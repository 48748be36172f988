"""End to end: simulate -> detect -> solve, and the solve API's answers to hard or bad input."""

import math

import numpy as np
import pytest

from startrack import Camera, Status
from startrack.errors import InvalidInputError
from startrack.frames import attitude_error, random_rotations, rotation_from_radec_roll
from startrack.identify import MatcherOptions
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.solve import solve_image, solve_stars
from startrack.units import ARCSEC, DEG

CAMERA = Camera.from_fov(1024, 1024, 15.0)
SENSOR = get_sensor_preset("generic-cmos")
PIXEL_ANGLE = CAMERA.pixel_scale_arcsec * ARCSEC

SPECIAL = [(0.0, 0.0, 0.0), (0.0, 89.99, 30.0), (123.0, 90.0, 0.0), (200.0, -90.0, 45.0), (359.999, -30.0, 359.0),
           (0.001, 45.0, 180.0)]


def _attitudes():
    special = [rotation_from_radec_roll(ra * DEG, dec * DEG, roll * DEG) for ra, dec, roll in SPECIAL]
    return special + list(random_rotations(6, rng=11))


@pytest.mark.parametrize("index", range(12))
def test_simulated_frames_solve_lost_in_space(index):
    truth = _attitudes()[index]
    sim = simulate_frame(CAMERA, truth, max_mag=7.5, sensor=SENSOR, rng=100 + index)
    solution = solve_image(sim.image)  # no FOV given: 5-35 deg searched
    detections = solution.detections
    assert solution.status is Status.OK, solution.reason
    assert attitude_error(truth, solution.rot_cam_from_icrs) < 2 * PIXEL_ANGLE
    assert solution.fov_deg == pytest.approx(15.0, rel=1e-3)
    assert solution.false_match_prob < 1e-6
    assert len(solution.matches) >= 10
    # every identified star is the catalog star the simulator put there
    det = solution.matches.det_index
    nearest = np.argmin(np.hypot(detections.x[det, None] - sim.truth.x, detections.y[det, None] - sim.truth.y), axis=1)
    assert np.mean(sim.truth.ids[nearest] == solution.matches.hip) > 0.95


def _star_list(seed, noise_px=0.2):
    rng = np.random.default_rng(seed)
    truth = random_rotations(None, rng)
    sim = simulate_frame(CAMERA, truth, max_mag=7.0, sensor=SENSOR, noise=False)
    inside = sim.truth.inside(margin_px=1.0)
    x = sim.truth.x[inside] + rng.normal(0, noise_px, inside.sum())
    y = sim.truth.y[inside] + rng.normal(0, noise_px, inside.sum())
    return truth, np.clip(x, 0, 1023), np.clip(y, 0, 1023)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_known_fov_and_camera_paths(seed):
    truth, x, y = _star_list(seed)
    for kwargs in ({"fov_deg": 15.2}, {"camera": CAMERA}, {"fov_range_deg": (10, 20)}):
        solution = solve_stars(x, y, width=1024, height=1024, **kwargs) if "camera" not in kwargs else \
            solve_stars(x, y, **kwargs)
        assert solution.solved, (kwargs, solution.reason)
        assert attitude_error(truth, solution.rot_cam_from_icrs) < PIXEL_ANGLE


@pytest.mark.parametrize("seed", [4, 5, 6])
def test_mirrored_star_list_is_refused(seed):
    _, x, y = _star_list(seed)
    solution = solve_stars(1023 - x, y, width=1024, height=1024, options=MatcherOptions(timeout_s=1.0))
    assert not solution.solved
    assert solution.status in (Status.NO_MATCH, Status.TIMEOUT)


@pytest.mark.parametrize("seed", [7, 8])
def test_only_false_stars_are_refused(seed):
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(0, 1023, 30), rng.uniform(0, 1023, 30)
    solution = solve_stars(x, y, width=1024, height=1024, options=MatcherOptions(timeout_s=1.0))
    assert not solution.solved
    assert solution.reason


def test_too_few_stars_is_a_status_not_an_exception():
    solution = solve_stars([10.0, 20.0, 30.0], [5.0, 50.0, 9.0], width=100, height=100)
    assert solution.status is Status.TOO_FEW_STARS
    assert "at least 4 stars" in solution.reason


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"x": [1.0, np.nan, 3, 4], "y": [1.0, 2, 3, 4]}, "finite"),
    ({"x": [1.0, 2, 3, 400], "y": [1.0, 2, 3, 4]}, "outside"),
    ({"x": [1.0, 2, 3], "y": [1.0, 2]}, "same length"),
    ({"fov_deg": -5.0}, "field of view"),
    ({"fov_deg": 500.0}, "field of view"),
    ({"fov_range_deg": (30.0, 10.0)}, "low <= high"),
    ({"fov_deg": 10.0, "fov_range_deg": (5.0, 20.0)}, "not both"),
    ({"width": 0}, "width"),
    ({"epoch": -4}, "epoch"),
])
def test_bad_input_is_refused_with_a_clear_message(kwargs, message):
    args = {"x": [1.0, 2, 3, 4], "y": [1.0, 2, 3, 4], "width": 100, "height": 100} | kwargs
    with pytest.raises(InvalidInputError, match=message):
        solve_stars(**args)


def test_flux_orders_the_stars():
    truth, x, y = _star_list(9)
    order = np.random.default_rng(0).permutation(len(x))
    flux = -np.arange(len(x), dtype=float)  # first of the true order is brightest
    solution = solve_stars(x[order], y[order], width=1024, height=1024, flux=flux[order])
    assert solution.solved
    assert attitude_error(truth, solution.rot_cam_from_icrs) < PIXEL_ANGLE


def test_distorted_camera_solves_with_its_focal_length_fixed():
    camera = Camera(width=1280, height=960, fx=4200.0, fy=4205.0, cx=650.0, cy=470.0, k1=-0.3, k2=0.2, p1=2e-4)
    truth = rotation_from_radec_roll(83.8 * DEG, -5.4 * DEG, 20 * DEG)
    sim = simulate_frame(camera, truth, max_mag=6.5, sensor=SENSOR, noise=False)
    inside = sim.truth.inside(margin_px=2.0)
    solution = solve_stars(sim.truth.x[inside], sim.truth.y[inside], camera=camera)
    assert solution.solved, solution.reason
    assert attitude_error(truth, solution.rot_cam_from_icrs) < 0.1 * camera.pixel_scale_arcsec * ARCSEC
    assert math.isclose(solution.fov_deg, camera.fov_deg)


def test_a_close_double_is_named_after_its_brighter_star():
    """HIP 42172 (V 5.9) and HIP 42173 (V 7.2) are 10 arcsec apart, a fraction of a Sunsat pixel:
    the image shows one spot, which must be identified as the brighter star."""
    from startrack.camera import get_preset
    from startrack.catalog import load_catalog

    camera = get_preset("sunsat")
    catalog = load_catalog()
    row = int(np.flatnonzero(catalog.hip == 42172)[0])
    target = catalog.take(np.array([row])).vectors(2000.0)[0]
    ra, dec = math.atan2(target[1], target[0]), math.asin(target[2])
    rot = rotation_from_radec_roll(ra + 2 * DEG, dec - 1 * DEG, 0.3)
    bright = catalog.brighter_than(6.5)
    vec = bright.vectors(2000.0) @ rot.as_matrix().T
    x, y = camera.vector_to_pixel(np.where(vec[:, 2:] > 0, vec, np.nan))
    seen = camera.in_image(x, y)
    order = np.argsort(bright.v_mag[seen])
    x, y = x[seen][order], y[seen][order]
    # A centroid error of a tenth of a pixel puts the spot nearer the faint companion.
    companion = catalog.take(np.flatnonzero(catalog.hip == 42173)).vectors(2000.0) @ rot.as_matrix().T
    cx, cy = camera.vector_to_pixel(companion)
    spot = int(np.flatnonzero(bright.hip[seen][order] == 42172)[0])
    x[spot], y[spot] = x[spot] + 0.7 * (cx[0] - x[spot]), y[spot] + 0.7 * (cy[0] - y[spot])
    sol = solve_stars(x, y, camera=camera)
    assert sol.status is Status.OK
    matched = dict(zip(sol.matches.det_index.tolist(), sol.matches.hip.tolist(), strict=True))
    assert matched.get(spot) == 42172
