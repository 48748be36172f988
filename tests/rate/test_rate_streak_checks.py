"""The streak rate on degenerate data (no measurable noise) and its refusal of bad arguments."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from streak_scenes import render_streak_scene, spin_rate, star_field

from startrack.camera import Camera
from startrack.errors import InvalidInputError
from startrack.rate import streak_rate
from startrack.rate._segment_fit import fit_segment
from startrack.units import DEG

CAMERA = Camera.from_fov(512, 512, fov_deg=15.0)
OMEGA = spin_rate(70 * DEG, 0.05, 0.4)  # rad/s
EXPOSURE = 0.2 * 15 * DEG / 0.05  # s: streaks of a fifth of the field


def _scene(**noise):
    rng = np.random.default_rng(80)
    return render_streak_scene(CAMERA, Rotation.random(random_state=rng), OMEGA, EXPOSURE,
                               star_field(CAMERA, OMEGA, EXPOSURE, 6, rng), rng.uniform(1e5, 3e5, 6), rng=rng,
                               **noise)


def test_an_image_without_background_noise_gives_a_rate():
    # an empty sky of exact zeros: the robust noise is 0, which the segment fit divided by
    scene = _scene(background_e=0.0, read_noise_e=0.0)
    result = streak_rate(scene.image, CAMERA, EXPOSURE, prior_omega_rad_s=OMEGA)
    assert result.rate.ok
    np.testing.assert_allclose(result.rate.omega_rad_s, OMEGA, atol=0.01 * 0.05)  # rad/s: 1 % of the rate


def test_a_zero_prior_rate_orders_nothing_as_no_prior():
    """A tracker at rest passes its zero rate as the prior: found in review to raise."""
    scene = _scene()
    without = streak_rate(scene.image, CAMERA, EXPOSURE)
    zero = streak_rate(scene.image, CAMERA, EXPOSURE, prior_omega_rad_s=np.zeros(3))
    assert zero.rate.ok and without.rate.ok
    np.testing.assert_array_equal(zero.rate.omega_rad_s, without.rate.omega_rad_s)


def test_the_segment_fit_reports_a_region_it_cannot_fit():
    roi = np.zeros((20, 20))
    roi[10, 5:15] = 100.0
    fit = fit_segment(roi, (0.0, 0.0), (9.5, 10.0), (1.0, 0.0), 0.0)  # no noise estimate
    assert not fit.ok and "noise" in fit.reason


@pytest.mark.parametrize(("change", "match"), [
    ({"exposure_s": 0.0}, "exposure_s"),
    ({"exposure_s": np.nan}, "exposure_s"),
    ({"bias_px": np.nan}, "bias_px"),
    ({"bias_px": np.inf}, "bias_px"),
    ({"prior_omega_rad_s": [np.nan, 0.0, 0.0]}, "prior_omega_rad_s"),
    ({"prior_omega_rad_s": [0.1, 0.0]}, "prior_omega_rad_s"),
    ({"endpoint_sigma_px": -1.0}, "endpoint_sigma_px"),
])
def test_bad_arguments_are_refused_by_name(change, match):
    kwargs = {"exposure_s": EXPOSURE, "detector": "harris"} | change
    with pytest.raises(InvalidInputError, match=match):
        streak_rate(np.zeros((64, 64)), CAMERA, **kwargs)
