"""Corner responses go to the right streak ends (Sease 2013 §3, Table 3.1's detectors).

These would have caught the association outliers of the Table 3.1 benchmark: a clump of noise
taken for a 6-px streak (an end 85-175 px from any star), long diagonal streaks rejected because
their bounding boxes take in pieces of other streaks, and Trajkovic's direction-dependent bias.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_rate_streaks import CAMERA, _match_truth, _scene

from startrack.rate._endpoints import DETECTORS, EndpointBias, calibrate_bias_model, locate_endpoints, streak_path
from startrack.rate._segment_fit import model_and_jacobian, segment_image
from startrack.rate._streak_detect import find_streaks
from startrack.rate._streak_rate import measure_streaks
from startrack.units import PIXEL


def test_noise_alone_gives_no_streak():
    rng = np.random.default_rng(3)
    noise = rng.poisson(20.0, (512, 512)) + rng.normal(0.0, 5.0, (512, 512))  # the scenes' sky and read noise
    assert find_streaks(noise).regions == []
    assert find_streaks(noise, min_area_px=4).regions == []  # the point-star setting


@pytest.fixture(scope="module")
def curved_scene():
    """4 streaks of half the field, 45 deg from the spin axis: curved, with bounding boxes that
    take in parts of the other streaks (the (45, 0.5) scene of test_rate_streaks)."""
    return _scene(55, 45, 0.5, stars=4)


@pytest.mark.parametrize("detector", DETECTORS)
def test_every_detector_keeps_every_long_curved_streak(curved_scene, detector):
    # Every streak must be kept and no end may be an outlier.
    scene = curved_scene
    meas = measure_streaks(scene.image, CAMERA, detector=detector)
    ends = np.stack([meas.ends_a, meas.ends_b], axis=1)
    assert len(ends) == len(scene.start_xy)
    errors = np.linalg.norm(ends - _match_truth(scene, ends), axis=2)
    assert np.max(errors) < 3.0 * PIXEL  # uncalibrated: the inward bias is at most 2.3 px


def test_other_streaks_in_the_roi_are_masked_out():
    ys, xs = np.mgrid[0:60, 0:90].astype(float)
    own = segment_image(xs, ys, np.array([45.0, 30.0]), 0.5, -30.0, 30.0, 500.0, 1.0)
    other = segment_image(xs, ys, np.array([85.0, 5.0]), 2.0, -20.0, 5.0, 900.0, 1.0)
    roi = own + other
    mask = other < 1.0
    truth = np.array([45.0, 30.0]) + np.outer([-30.0, 30.0], [np.cos(0.5), np.sin(0.5)])
    found = locate_endpoints(roi, detector="min_eigenvalue", mask=mask)
    assert found.ok
    order = np.argsort(found.xy[:, 0])
    assert np.max(np.linalg.norm(found.xy[order] - truth, axis=1)) < 1.0 * PIXEL
    assert not locate_endpoints(roi, detector="min_eigenvalue").ok  # the other streak's corners


def test_streak_path_follows_a_curved_streak():
    ys, xs = np.mgrid[0:80, 0:140].astype(float)
    roi = segment_image(xs, ys, np.array([70.0, 40.0]), 0.0, -60.0, 60.0, 400.0, 1.0, curvature=0.01)
    path = streak_path(roi)
    ends = path.ends()
    truth = np.array([[10.0, 40.0 + 18.0], [130.0, 40.0 + 18.0]])  # d = curvature t^2 / 2 = 18 px
    assert np.max(np.linalg.norm(ends[np.argsort(ends[:, 0])] - truth, axis=1)) < 2.0 * PIXEL
    on_path = np.array([[70.0, 40.0], [40.0, 44.5]])
    assert np.max(path.offsets(on_path)) < 0.5 * PIXEL


def test_direction_dependent_bias_is_recovered():
    rng = np.random.default_rng(4)
    angles = rng.uniform(0, np.pi, 40)
    model = EndpointBias(np.array([1.6, -0.45, 0.05]))
    u = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    truth = np.stack([100.0 - 40 * u, 100.0 + 40 * u], axis=1)
    inward = np.array([model.at(d) for d in u])
    measured = truth + np.stack([inward[:, None] * u, -inward[:, None] * u], axis=1)
    fitted = calibrate_bias_model(measured, truth)
    np.testing.assert_allclose(fitted.coeffs, model.coeffs, atol=1e-9)
    assert fitted.at([1.0, 0.0]) == pytest.approx(fitted.at([-1.0, 0.0])) == pytest.approx(1.15)
    assert float(fitted) == pytest.approx(1.6)
    parallel = calibrate_bias_model(measured[:1].repeat(20, axis=0), truth[:1].repeat(20, axis=0))
    np.testing.assert_allclose(parallel.coeffs[1:], 0.0)  # one direction fixes only the mean


def test_segment_jacobian_matches_finite_differences():
    rng = np.random.default_rng(5)
    xs, ys = rng.uniform(-20, 20, (2, 300))
    centroid = np.array([1.0, -2.0])
    p = np.array([0.7, 0.4, -10.0, 12.0, 50.0, 1.3, 2.0, 0.03])
    _, jac = model_and_jacobian(p, xs, ys, centroid)
    step = 1e-6 * np.maximum(1.0, np.abs(p))
    model = lambda q: model_and_jacobian(q, xs, ys, centroid)[0]  # noqa: E731
    numeric = np.stack([(model(p + h) - model(p - h)) / (2 * h[k]) for k, h in enumerate(np.diag(step))], axis=1)
    np.testing.assert_allclose(jac, numeric, rtol=1e-5, atol=1e-5)
