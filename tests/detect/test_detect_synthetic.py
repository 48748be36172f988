"""The detector on synthetic star fields with known truth (tests/detect/star_render.py)."""

from __future__ import annotations

import numpy as np
import pytest
from star_render import random_positions, render_stars

from startrack.detect import StarDetector, detect
from startrack.results import Detections
from startrack.units import PIXEL

SHAPE = (256, 256)


def _match(det: Detections, x, y, tol: float = 1.0 * PIXEL):
    """Index of the detection nearest each true star, and whether it is within ``tol``."""
    if len(det) == 0:
        return np.zeros(len(x), dtype=int), np.zeros(len(x), dtype=bool)
    dist = np.hypot(x[:, None] - det.x[None], y[:, None] - det.y[None])
    return dist.argmin(axis=1), dist.min(axis=1) < tol


def _field(seed, n=25, flux=2e4, sigma_px=1.3, read_noise=3.0, shape=SHAPE, **kwargs):
    rng = np.random.default_rng(seed)
    x, y = random_positions(n, shape, margin=15, min_sep=20, rng=rng)
    flux = np.broadcast_to(flux, x.shape)
    image = render_stars(shape, x, y, flux, sigma_px=sigma_px, background=100.0,
                         read_noise=read_noise, rng=rng, **kwargs)
    return image, x, y, flux


@pytest.mark.parametrize("sigma_px", [0.8, 1.3, 2.5])
def test_high_snr_centroids_within_005_px(sigma_px):
    image, x, y, _ = _field(seed=1, sigma_px=sigma_px)
    det = detect(image)
    index, ok = _match(det, x, y)
    assert ok.all() and len(det) == len(x)
    err = np.concatenate([det.x[index] - x, det.y[index] - y])
    assert np.max(np.abs(err)) < 0.05 * PIXEL


def test_positions_are_column_row_in_a_non_square_image():
    x, y = np.array([100.3]), np.array([40.7])
    image = render_stars((80, 200), x, y, [5e4], sigma_px=1.2, background=10.0)
    det = detect(image)
    assert len(det) == 1
    assert det.x[0] == pytest.approx(100.3, abs=0.02 * PIXEL)
    assert det.y[0] == pytest.approx(40.7, abs=0.02 * PIXEL)


def test_brightest_first_and_flux_measured():
    rng = np.random.default_rng(2)
    x, y = random_positions(12, SHAPE, margin=15, min_sep=25, rng=rng)
    flux = rng.permutation(np.geomspace(1e3, 1e5, 12))
    image = render_stars(SHAPE, x, y, flux, sigma_px=1.3, background=50.0, read_noise=2.0, rng=rng)
    det = detect(image)
    index, ok = _match(det, x, y)
    assert ok.all() and len(det) == 12
    assert np.all(np.diff(det.flux) <= 0)
    # the i-th detection is the i-th brightest star
    np.testing.assert_array_equal(index[np.argsort(-flux)], np.arange(12))
    np.testing.assert_allclose(det.flux[index], flux, rtol=0.05)


def test_max_stars_keeps_the_brightest():
    image, x, y, _ = _field(seed=3, flux=np.geomspace(2e3, 5e4, 25))
    det = detect(image, max_stars=5)
    assert len(det) == 5
    assert det.flux.min() >= detect(image).flux[4] - 1e-9


def test_pure_noise_gives_almost_no_detections():
    counts = []
    for seed in range(6):
        rng = np.random.default_rng(seed)
        counts.append(len(detect(rng.normal(300.0, 8.0, (1024, 1024)).astype(np.float32))))
    for seed in range(6):
        rng = np.random.default_rng(100 + seed)
        noise = np.clip(np.rint(rng.normal(12.0, 1.2, (512, 512))), 0, None).astype(np.uint16)
        counts.append(len(detect(noise)))
    assert np.mean(counts) < 3, counts


def test_hot_pixels_are_rejected():
    image, x, y, _ = _field(seed=4, n=10, flux=1e4)
    rng = np.random.default_rng(5)
    hot_y, hot_x = rng.integers(5, SHAPE[0] - 5, 80), rng.integers(5, SHAPE[1] - 5, 80)
    clear = np.hypot(x[:, None] - hot_x, y[:, None] - hot_y).min(axis=0) > 10
    hot_y, hot_x = hot_y[clear][:40], hot_x[clear][:40]
    image[hot_y, hot_x] += rng.uniform(300, 3000, hot_x.size)
    det = detect(image)
    _, ok = _match(det, x, y, tol=0.2 * PIXEL)
    assert ok.all()
    assert len(det) == len(x)
    assert len(detect(image, max_peak_fraction=None)) > len(x) + 20  # the filter does the work


def test_edge_spots_are_rejected():
    x, y = np.array([0.6, 128.0, 255.0, 60.0]), np.array([100.0, 128.0, 30.0, 0.2])
    image = render_stars(SHAPE, x, y, [2e4] * 4, sigma_px=1.3, background=100.0, read_noise=2.0,
                         rng=6)
    det = detect(image)
    assert len(det) == 1 and det.x[0] == pytest.approx(128.0, abs=0.05 * PIXEL)
    assert len(detect(image, reject_edge=False)) == 4


def test_a_bright_star_a_few_pixels_inside_is_kept_and_a_glow_there_is_not():
    """Found by a crop of a real frame: its brightest star, 4 px inside, was dropped because its
    threshold core (hundreds of px) reached the border; its half-maximum core does not. A glow of
    the same flux and place, 6 px wide, is cut by the border at its half maximum and goes. (The
    full-resolution pass, which a frame of fewer than three stars runs, is off: it has an edge
    filter of its own and found the star itself.)"""
    x, y = np.array([128.0, 60.0]), np.array([4.0, 128.0])
    star = render_stars(SHAPE, x[:1], y[:1], [2e6], sigma_px=1.3, background=100.0, read_noise=2.0, rng=9)
    det = detect(star, fine_sigma=None)
    assert len(det) == 1 and det.area_px[0] > 64
    assert np.hypot(det.x[0] - x[0], det.y[0] - y[0]) < 0.05 * PIXEL
    glow = render_stars(SHAPE, x[:1], y[:1], [2e6], sigma_px=6.0, background=100.0, read_noise=2.0, rng=9)
    glow += render_stars(SHAPE, x[1:], y[1:], [2e4], sigma_px=1.3, background=0.0, read_noise=0.0, rng=9)
    det = detect(glow, fine_sigma=None)
    assert len(det) == 1 and np.hypot(det.x[0] - x[1], det.y[0] - y[1]) < 0.05 * PIXEL


def test_close_pair_is_deblended():
    x, y = np.array([100.0, 107.3]), np.array([120.0, 121.5])
    image = render_stars(SHAPE, x, y, [3e4, 1.5e4], sigma_px=1.3, background=100.0,
                         read_noise=2.0, rng=7)
    det = detect(image)
    index, ok = _match(det, x, y, tol=0.3 * PIXEL)
    assert len(det) == 2 and ok.all()
    assert len(detect(image, deblend=False)) == 1


def test_streaks_are_rejected_by_elongation():
    x = np.linspace(60.0, 90.0, 40)
    image = render_stars(SHAPE, x, np.full(40, 128.0), np.full(40, 500.0), sigma_px=1.0,
                         background=100.0, read_noise=2.0, rng=8)
    det = detect(image, max_elongation=None)
    assert len(det) == 1 and det.elongation[0] > 5
    assert len(detect(image)) == 0


def test_tiled_background_copes_with_a_strong_gradient():
    image, x, y, _ = _field(seed=9, flux=5e3)
    ramp = np.linspace(0.0, 3000.0, SHAPE[1])[None, :] + np.linspace(0, 1000, SHAPE[0])[:, None]
    det = detect(image + ramp)
    _, ok = _match(det, x, y, tol=0.3 * PIXEL)
    assert ok.all() and len(det) == len(x)
    assert len(detect(image + ramp, background="global")) != len(x)


@pytest.mark.parametrize("kwargs", [{"binning": 1}, {"binning": 3}, {"kernel": "box"},
                                    {"kernel_px": 1}, {"background": "global"},
                                    {"grow_sigma": 5.0}, {"uncertainty": "eq4.2"}])
def test_other_settings_still_find_the_stars(kwargs):
    image, x, y, _ = _field(seed=10, flux=1e4)
    det = StarDetector(**kwargs).detect(image)
    index, ok = _match(det, x, y, tol=0.1 * PIXEL)
    assert ok.all() and len(det) == len(x)


def test_propagated_sigma_matches_the_scatter():
    errors, sigmas = [], []
    for seed in range(6):
        image, x, y, _ = _field(seed=20 + seed, flux=3e3, read_noise=5.0)
        det = detect(image)
        index, ok = _match(det, x, y)
        assert ok.all()
        errors.append(np.concatenate([det.x[index] - x, det.y[index] - y]))
        sigmas.append(np.tile(det.sigma_px[index], 2))
    errors, sigmas = np.concatenate(errors), np.concatenate(sigmas)
    ratio = np.sqrt(np.mean(errors**2)) / np.sqrt(np.mean(sigmas**2))
    assert 0.8 < ratio < 1.25, ratio
    assert abs(np.mean(errors)) < 0.01 * PIXEL  # no bias


def test_eq42_sigma_is_the_seed_curve():
    image, x, y, _ = _field(seed=30, flux=np.geomspace(1e3, 1e5, 25), read_noise=4.0)
    det = detect(image, uncertainty="eq4.2", background="global")  # one noise for all
    snr = det.peak / det.noise
    np.testing.assert_allclose(det.sigma_px, 0.11 + 0.5 * snr**-1.3, rtol=1e-6)
    assert np.all(det.sigma_px >= 0.11)


def test_noise_free_image_is_detected():
    x, y = np.array([50.2, 150.7]), np.array([60.4, 180.9])
    image = render_stars(SHAPE, x, y, [1e3, 3e3], sigma_px=1.5, background=0.0)
    det = detect(image)
    index, ok = _match(det, x, y, tol=0.01 * PIXEL)
    assert ok.all() and len(det) == 2
