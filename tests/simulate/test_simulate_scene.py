"""render_stars on synthetic star fields: truth, photometry, centroids, noise, edges, misuse."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from scipy.stats import norm

from startrack.camera import Camera
from startrack.errors import InvalidInputError
from startrack.frames import boresight
from startrack.simulate import (
    NoiseModel,
    field_radius_rad,
    get_sensor_preset,
    random_attitude,
    render_stars,
)
from startrack.units import DEG, PIXEL

SHOT_AND_READ = NoiseModel(quantize=False, saturate=False)


def box(image, x, y, half):
    """The square of half-width ``half`` pixels around the pixel nearest (x, y)."""
    xi, yi = round(x), round(y)
    return image[yi - half:yi + half + 1, xi - half:xi + half + 1]


def test_truth_positions_are_the_camera_projection(small_camera, rot, plain_sensor, vectors_at):
    x, y = np.array([20.25, 70.6, 48.0]), np.array([15.5, 60.1, 39.9])
    v = vectors_at(small_camera, rot, x, y)
    sim = render_stars(small_camera, rot, v, [3.0, 1.0, 2.0], [11, 22, 33], sensor=plain_sensor,
                       noise=False)
    np.testing.assert_array_equal(sim.truth.ids, [22, 33, 11])  # brightest first
    np.testing.assert_array_equal(sim.truth.mag, [1.0, 2.0, 3.0])
    order = [1, 2, 0]
    assert np.max(np.abs(sim.truth.x - x[order])) < 1e-9 * PIXEL
    assert np.max(np.abs(sim.truth.y - y[order])) < 1e-9 * PIXEL
    px, py = small_camera.vector_to_pixel(rot.apply(sim.truth.vectors_icrs))
    np.testing.assert_allclose(px, sim.truth.x, atol=1e-12)
    np.testing.assert_allclose(py, sim.truth.y, atol=1e-12)
    np.testing.assert_allclose(sim.truth.electrons, plain_sensor.electrons(sim.truth.mag))
    assert sim.truth.exposure_s == plain_sensor.exposure_s
    assert sim.truth.rot_cam_from_icrs is rot and sim.truth.camera is small_camera


def test_noise_free_star_has_its_electrons_and_its_centroid(small_camera, rot, plain_sensor,
                                                            vectors_at):
    x, y = 47.37, 41.82
    sim = render_stars(small_camera, rot, vectors_at(small_camera, rot, [x], [y]), [4.0], [1],
                       sensor=plain_sensor, background_e=12.0, noise=False)
    star = (sim.image - sim.truth.background_adu) * plain_sensor.detector.gain_e_per_adu
    assert star.sum() == pytest.approx(sim.truth.electrons[0], rel=1e-3)
    rows, cols = np.indices(star.shape)
    assert abs((cols * star).sum() / star.sum() - x) < 0.01 * PIXEL
    assert abs((rows * star).sum() / star.sum() - y) < 0.01 * PIXEL


def test_summed_star_counts_are_consistent_with_shot_and_read_noise(small_camera, rot,
                                                                    plain_sensor, vectors_at):
    x, y, half = 50.2, 38.7, 6
    v = vectors_at(small_camera, rot, [x], [y])
    rng = np.random.default_rng(11)
    sums = np.array([
        box(render_stars(small_camera, rot, v, [6.0], [1], sensor=plain_sensor, rng=rng,
                         noise=SHOT_AND_READ).image, x, y, half).sum()
        for _ in range(300)])
    det = plain_sensor.detector
    npix = (2 * half + 1) ** 2
    signal = float(plain_sensor.electrons(6.0))
    in_box = signal * (norm.cdf(half + 0.5, scale=1.5) - norm.cdf(-half - 0.5, scale=1.5)) ** 2
    mean_e = in_box + npix * plain_sensor.dark_e
    var_e = mean_e + npix * det.read_noise_e**2
    sums_e = (sums - npix * det.bias_adu) * det.gain_e_per_adu
    assert abs(sums_e.mean() - mean_e) < 4 * np.sqrt(var_e / sums.size)
    assert sums_e.var(ddof=1) == pytest.approx(var_e, rel=0.25)  # 3 sigma of a 300-sample var


def test_same_seed_gives_a_bit_identical_image(small_camera, rot, plain_sensor, vectors_at):
    v = vectors_at(small_camera, rot, [30.0, 60.0], [30.0, 50.0])
    a, b, c = (render_stars(small_camera, rot, v, [2.0, 3.0], [1, 2], sensor=plain_sensor, rng=seed)
               for seed in (5, 5, 6))
    assert a.image.dtype == np.uint16
    np.testing.assert_array_equal(a.image, b.image)
    assert np.any(a.image != c.image)


def test_bright_star_saturates_at_the_adc_maximum(rot, vectors_at):
    camera = Camera.from_fov(64, 64, 10.0)
    sensor = get_sensor_preset("far-mst")
    sim = render_stars(camera, rot, vectors_at(camera, rot, [32.0], [32.0]), [-6.0], [1],
                       sensor=sensor, rng=0)
    assert sim.image.max() == sensor.detector.max_adu
    assert sim.image[32, 32] == sensor.detector.max_adu


def test_star_centred_off_the_edge_is_clipped_and_kept_in_the_truth(small_camera, rot,
                                                                     plain_sensor, vectors_at):
    x, y, sigma = -1.5, 40.3, plain_sensor.psf_sigma_px
    v = vectors_at(small_camera, rot, [x, -60.0], [y, 40.0])  # the second is far outside
    sim = render_stars(small_camera, rot, v, [3.0, 0.0], [7, 8], sensor=plain_sensor,
                       noise=False)
    np.testing.assert_array_equal(sim.truth.ids, [7])
    assert not sim.truth.inside()[0]
    star = (sim.image - sim.truth.background_adu) * plain_sensor.detector.gain_e_per_adu
    fraction = 1.0 - norm.cdf(-0.5, loc=x, scale=sigma)
    assert star.sum() == pytest.approx(sim.truth.electrons[0] * fraction, rel=1e-5)


def test_stars_behind_the_camera_are_not_rendered(small_camera, rot, plain_sensor, vectors_at):
    v = vectors_at(small_camera, rot, [40.0], [40.0])
    sim = render_stars(small_camera, rot, -v, [1.0], [1], sensor=plain_sensor, noise=False)
    assert len(sim.truth) == 0
    np.testing.assert_allclose(sim.image, sim.truth.background_adu)


def test_distorted_camera_positions_follow_the_distortion_model(rot, plain_sensor):
    camera = Camera.from_fov(120, 90, 20.0, k1=-0.2, p1=1e-3)
    v_cam = np.array([[0.12, 0.1, 1.0], [-0.15, 0.02, 1.0], [0.0, -0.1, 1.0]])
    v_cam /= np.linalg.norm(v_cam, axis=1, keepdims=True)
    sim = render_stars(camera, rot, rot.inv().apply(v_cam), [1.0, 2.0, 3.0], [1, 2, 3],
                       sensor=plain_sensor, noise=False)
    x, y = camera.vector_to_pixel(v_cam)
    np.testing.assert_allclose(sim.truth.x, x, atol=1e-9)
    np.testing.assert_allclose(sim.truth.y, y, atol=1e-9)


def test_field_radius_reaches_the_corners(small_camera):
    half_diagonal = small_camera.fov_diagonal_deg * DEG / 2
    assert half_diagonal < field_radius_rad(small_camera) < 1.02 * half_diagonal


def test_random_attitude_is_seeded_and_uniform():
    assert random_attitude(3).approx_equal(random_attitude(3))
    axes = np.array([boresight(random_attitude(rng)) for rng in range(400)])
    assert np.linalg.norm(axes.mean(axis=0)) < 0.15  # uniform: mean ~ 0 +- 0.05 per axis


@pytest.mark.parametrize("change", [
    {"star_vectors_icrs": np.zeros((2, 2))},
    {"mags": [1.0]},
    {"ids": [1.5, 2.5]},
    {"rot_cam_from_icrs": Rotation.identity(2)},
    {"noise": "maybe"},
])
def test_misuse_raises(small_camera, rot, change):
    args = {"camera": small_camera, "rot_cam_from_icrs": rot,
            "star_vectors_icrs": [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]], "mags": [1.0, 2.0],
            "ids": [1, 2]}
    with pytest.raises(InvalidInputError):
        render_stars(**{**args, **change})


def test_truth_keeps_exactly_the_stars_whose_stamp_reaches_the_image(small_camera, rot,
                                                                     plain_sensor, vectors_at):
    radius = 8  # ceil(5 * 1.5): the stamp half-width of the plain sensor
    x = np.array([-radius - 0.49, -radius - 0.51, 95 + radius + 0.49, 95 + radius + 0.51])
    v = vectors_at(small_camera, rot, x, np.full(4, 40.0))
    sim = render_stars(small_camera, rot, v, [1.0, 2.0, 3.0, 4.0], [1, 2, 3, 4],
                       sensor=plain_sensor, noise=False)
    np.testing.assert_array_equal(sim.truth.ids, [1, 3])
    lit = sim.image - sim.truth.background_adu
    assert lit[:, 0].max() > 0 and lit[:, -1].max() > 0
