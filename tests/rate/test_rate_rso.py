"""RSO indicators of Sease 2013 ch. 4 (Sease 2013 Ch.4 Eq. 4.11–4.15): the RSO flagged, no star flagged."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from streak_scenes import render_streak_scene, spin_rate

from startrack.camera import Camera
from startrack.errors import InvalidInputError
from startrack.rate._catalog_free import catalog_free_rate
from startrack.rate._rso import INDICATORS, rso_indicators, spin_axis, turn_angles
from startrack.rate._streak_rate import streak_rate
from startrack.units import DEG

CAMERA = Camera.from_fov(1024, 1024, fov_deg=20.0)
RATE = 0.05  # rad/s: 0.025 rad, 73 px, in 0.5 s
EXPOSURE = 0.5
ABOUT_Y = np.array([0.0, RATE, 0.0])  # spin axis in the focal plane: no centre of rotation in the image
HARRIS_BIAS_PX = 0.64


def _own(vector, along, across, axis=(0.0, 1.0, 0.0)):
    """An object's own rate (rad/s, camera axes) at camera ``vector``: ``along`` about ``axis``
    (along the stars' motion when the camera turns about it) and ``across`` it."""
    east = np.cross(axis, vector)
    north = np.cross(vector, east)
    return along * east / np.linalg.norm(east) + across * north / np.linalg.norm(north)


def _ends(vectors, omega, own_last=None):
    """Exact pixel ends (N, 2) at the start and at the end of the exposure of objects at camera
    vectors (N, 3) (at the start); the last one's sight line also turns at ``own_last`` (rad/s)."""
    later = np.array(vectors, dtype=float)
    if own_last is not None:
        later[-1] = Rotation.from_rotvec(np.asarray(own_last) * EXPOSURE).apply(later[-1])
    later = Rotation.from_rotvec(-np.asarray(omega) * EXPOSURE).apply(later)
    return np.stack(CAMERA.vector_to_pixel(vectors), axis=1), np.stack(CAMERA.vector_to_pixel(later), axis=1)


def _random_frame(rng, omega, stars=15, own=(0.2 * RATE, 0.2 * RATE)):
    """Exact ends of ``stars`` stars whose paths stay in the image, then one RSO (the last)."""
    xy = rng.uniform(100, CAMERA.width - 101, (4 * stars, 2))
    vectors = CAMERA.pixel_to_vector(xy[:, 0], xy[:, 1])
    start, end = _ends(vectors, omega)
    inside = CAMERA.in_image(end[:, 0], end[:, 1], 20.0)
    vectors = vectors[inside][: stars + 1]
    return _ends(vectors, omega, _own(vectors[-1], *own, axis=omega))


def _indicators(start, end, sigma_px, **options):
    """The indicators of noisy ends, with the OLAE residuals of the catalog-free rate."""
    va, vb = CAMERA.pixel_to_vector(*start.T), CAMERA.pixel_to_vector(*end.T)
    fit = catalog_free_rate(va, vb, EXPOSURE, floor_rad=1e-9)
    return rso_indicators(start, end, CAMERA, fit.residuals, endpoint_sigma_px=sigma_px, **options)


@pytest.mark.parametrize("theta_deg", [5.0, 45.0, 90.0])
def test_spin_axis_is_the_centre_of_rotation_on_the_sphere(theta_deg):
    rng = np.random.default_rng(1)
    omega = spin_rate(theta_deg * DEG, RATE, 0.7)
    start, end = _random_frame(rng, omega, own=(0.3 * RATE, 0.3 * RATE))
    va, vb = CAMERA.pixel_to_vector(*start.T), CAMERA.pixel_to_vector(*end.T)
    axis, offsets = spin_axis(va, vb)
    assert np.degrees(np.arccos(np.clip(-axis @ omega / RATE, -1, 1))) < 1e-6  # the stars turn about -omega
    assert np.max(np.abs(offsets[:-1])) < 1e-9 and abs(offsets[-1]) > 1e-3
    np.testing.assert_allclose(turn_angles(va, vb, axis)[:-1], RATE * EXPOSURE, rtol=1e-9)


@pytest.mark.parametrize("theta_deg", [90.0, 60.0, 20.0])
def test_no_star_flagged_across_a_wide_field(theta_deg):
    # Ends 0.03 px rms off (the segment fit's measured accuracy on bright streaks): in the image
    # plane, streaks near the corners are up to 5 % longer and tilted by up to 2.4 deg, which
    # flagged a few % of the stars; on the sphere they all turn alike.
    rng = np.random.default_rng(2)
    flagged = {name: 0 for name in INDICATORS}
    for _ in range(30):
        omega = spin_rate(theta_deg * DEG, RATE, rng.uniform(0, 2 * np.pi))
        start, end = _random_frame(rng, omega)
        start, end = start + rng.normal(0, 0.03, start.shape), end + rng.normal(0, 0.03, end.shape)
        rso = _indicators(start, end, 0.01)  # the fit's own (photon-noise) sigma of a bright streak
        for name in INDICATORS:
            assert rso.flags[name][-1]  # the RSO, off by 0.2 of the rate both ways: 12 px
            flagged[name] += int(rso.flags[name][:-1].sum())
    assert flagged == {name: 0 for name in INDICATORS}


def test_scatter_expected_per_streak():
    # Stars with ends from 0.1 to 2 px precise: each is judged by its own expected scatter, so
    # the imprecise ones are not the ones flagged (about 1.2 % at k = 2.5 for Gaussian errors).
    rng = np.random.default_rng(3)
    flagged = np.zeros(3)
    total = 0
    for _ in range(60):
        start, end = _random_frame(rng, ABOUT_Y, stars=16, own=(0.4 * RATE, 0.4 * RATE))
        sigma = np.geomspace(0.1, 2.0, len(start))
        start = start + rng.normal(0, 1, start.shape) * sigma[:, None]
        end = end + rng.normal(0, 1, end.shape) * sigma[:, None]
        rso = _indicators(start[:-1], end[:-1], sigma[:-1])  # stars only
        noisy = np.arange(len(start) - 1) >= (len(start) - 1) // 2
        flagged += [rso.flags[name][noisy].sum() for name in INDICATORS]
        total += noisy.sum()
    assert np.all(flagged / total < 0.04)


def test_streak_cut_by_the_border_is_judged_by_the_centre_of_rotation_only():
    # A star leaving the image mid-exposure: its last end is where it crossed the border, so it
    # turned through a smaller angle than the stars and misfits their rotation; its bisector
    # still holds the spin axis.
    rng = np.random.default_rng(4)
    start, end = _random_frame(rng, ABOUT_Y)
    vector = CAMERA.pixel_to_vector(60.0, 500.0)  # moves towards -x, leaves at x = 0
    s, e = _ends(vector[None], ABOUT_Y)
    cut = s + (e - s) * (s[0, 0] - 0.0) / (s[0, 0] - e[0, 0])
    start, end = np.vstack([start[:-1], s, start[-1:]]), np.vstack([end[:-1], cut, end[-1:]])
    i = len(start) - 2
    rso = _indicators(start, end, 0.1)
    assert rso.truncated[i] and np.sum(rso.truncated) == 1
    assert not any(rso.flags[name][i] for name in INDICATORS)
    assert np.isnan(rso.values["angular_displacement"][i]) and np.isnan(rso.values["combined"][i])
    assert abs(rso.z["centre_of_rotation"][i]) < 1.0
    assert rso.flags["combined"][-1] and np.sum(rso.flags["combined"]) == 1
    unmarked = _indicators(start, end, 0.1, edge_margin_px=0.0)  # taken as whole, it is an outlier
    assert unmarked.flags["angular_displacement"][i] and unmarked.flags["combined"][i]


def test_misuse_is_refused():
    with pytest.raises(InvalidInputError, match="N >= 2"):
        rso_indicators(np.zeros((1, 2)), np.ones((1, 2)), CAMERA, np.zeros(1))
    with pytest.raises(InvalidInputError, match="differ"):
        rso_indicators(np.ones((3, 2)), np.ones((3, 2)), CAMERA, np.zeros(3))


def _grid_scene(omega, rng):
    """A rendered frame: 16 stars on a grid, one star leaving the image at the left, an RSO."""
    gx, gy = np.meshgrid(np.linspace(150, 900, 4), np.linspace(80, 940, 4))
    xy = np.vstack([np.stack([gx.ravel(), gy.ravel()], axis=1), [[55.0, 510.0], [520.0, 510.0]]])
    vectors = CAMERA.pixel_to_vector(xy[:, 0], xy[:, 1])
    own = np.zeros((len(vectors), 3))
    own[-1] = _own(vectors[-1], 0.3 * RATE, 0.3 * RATE, axis=omega)
    return render_streak_scene(CAMERA, Rotation.from_rotvec([0.3, 0.2, 0.1]), omega, EXPOSURE, vectors,
                               rng.uniform(1e5, 5e5, len(vectors)), rso_omega_cam=own, rng=rng)


@pytest.mark.parametrize("theta_deg, detector, bias", [(90.0, "segment", 0.0), (45.0, "segment", 0.0),
                                                       (90.0, "harris", HARRIS_BIAS_PX)])
def test_rso_flagged_and_no_star_in_a_simulated_frame(theta_deg, detector, bias):
    rng = np.random.default_rng(5)
    omega = spin_rate(theta_deg * DEG, RATE, 0.5 * np.pi)  # 90 deg: about camera y
    scene = _grid_scene(omega, rng)
    result = streak_rate(scene.image, CAMERA, EXPOSURE, detector=detector, bias_px=bias, prior_omega_rad_s=omega)
    meas = result.measurement
    ends = np.stack([meas.ends_a, meas.ends_b], axis=1)
    truth = np.stack([scene.start_xy[-1], scene.end_xy[-1]])
    misfit = np.minimum(np.linalg.norm(ends - truth, axis=2).max(axis=1),
                        np.linalg.norm(ends - truth[::-1], axis=2).max(axis=1))
    rso = int(np.argmin(misfit))
    assert misfit[rso] < 1.0 and len(ends) >= 16
    np.testing.assert_array_equal(result.rso.candidates, [rso])
    for name in INDICATORS:  # the RSO moves both along and across the stars: each indicator sees it
        np.testing.assert_array_equal(np.flatnonzero(result.rso.flags[name]), [rso])
    assert not result.rate.used[rso] and np.linalg.norm(result.rate.omega_rad_s - omega) < 0.01 * RATE
