"""Centroiders and the Cramér-Rao bound: reference values, noise-free recovery, seeded Monte
Carlo against the bound, and every method by name through the detector."""

from __future__ import annotations

import numpy as np
import pytest
from star_render import pixel_fractions, random_positions, render_stars

from startrack.detect import StarDetector, detect
from startrack.detect import _crb as crb
from startrack.detect._centroid_mle import mle_centroid
from startrack.detect._centroid_windowed import windowed_centroid
from startrack.detect._centroiders import CENTROIDERS
from startrack.detect._windows import Windows, extract_windows
from startrack.units import PIXEL

# --- the bound ---------------------------------------------------------------------------------


def test_crb_meets_the_closed_forms():
    # photon-limited, well sampled: s / sqrt(F)
    assert crb.crb_sigma_px(1e6, 2.0, nuisance=False) == pytest.approx(2.0 / 1e3, rel=0.02)
    # background-limited: sqrt(8 pi) s^2 sigma_N / F
    bound = crb.crb_sigma_px(200.0, 2.0, 1e4, 10.0, nuisance=False)
    assert bound == pytest.approx(crb.crb_background_limited_px(200.0, 2.0, np.sqrt(1e4 + 100)),
                                  rel=0.03)


def test_crb_grows_with_each_unknown_and_shrinks_with_flux():
    known = crb.crb_sigma_px(3e3, 1.5, 100.0, 5.0, nuisance=False)
    nuisance = crb.crb_sigma_px(3e3, 1.5, 100.0, 5.0)
    width = crb.crb_sigma_px(3e3, 1.5, 100.0, 5.0, fit_sigma=True)
    assert known <= nuisance <= width * (1 + 1e-12)
    assert np.all(np.diff(crb.crb_sigma_px(np.geomspace(1e2, 1e6, 5), 1.5, 100.0, 5.0)) < 0)


def test_crb_shapes_and_bad_input():
    out = crb.crb_sigma_px(np.array([1e3, 1e4]), 1.5, 10.0, x_phase_px=np.array([[0.0], [0.5]]))
    assert out.shape == (2, 2)
    with pytest.raises(ValueError, match="psf_sigma_px"):
        crb.crb_sigma_px(1e3, 0.0)
    with pytest.raises(ValueError, match="flux_e"):
        crb.crb_sigma_px(-1.0, 1.0)


def test_snr_and_flux_are_inverse():
    flux = crb.flux_for_snr([5.0, 20.0, 500.0], 1.5, 100.0, 5.0)
    np.testing.assert_allclose(crb.integrated_snr(flux, 1.5, 100.0, 5.0), [5.0, 20.0, 500.0])


# --- noise-free recovery -----------------------------------------------------------------------


def _stamps(xs, ys, flux, sigma_px, background=0.0, size=21):
    """Pixel-integrated Gaussian stars (tests/detect/star_render.py), one per window."""
    half = size // 2
    cx, cy = np.rint(xs).astype(int), np.rint(ys).astype(int)
    values = np.stack([background + f * np.outer(pixel_fractions(y, sigma_px, y0 - half, y0 + half + 1),
                                                 pixel_fractions(x, sigma_px, x0 - half, x0 + half + 1))
                       for x, y, x0, y0, f in zip(xs, ys, cx, cy, flux, strict=True)])
    return Windows(values, cx - half, cy - half)


@pytest.mark.parametrize(("sigma_px", "window_bias"), [(0.7, 0.05 * PIXEL), (1.5, 1e-3 * PIXEL),
                                                       (2.5, 1e-3 * PIXEL)])
def test_windowed_and_mle_recover_noise_free_positions(sigma_px, window_bias):
    """The MLE is exact; the Gaussian window is exact for well-sampled stars and has a
    pixel-phase bias for undersampled ones (sigma 0.7 px: up to 0.04 px)."""
    rng = np.random.default_rng(1)
    xs, ys = 50 + rng.uniform(-0.5, 0.5, 12), 40 + rng.uniform(-0.5, 0.5, 12)
    win = _stamps(xs, ys, np.full(12, 1e4), sigma_px, background=20.0)
    level, noise = np.full(12, 20.0), np.ones(12)
    start_x, start_y = np.rint(xs).astype(float), np.rint(ys).astype(float)
    w = windowed_centroid(win, level, noise, start_x, start_y, sigma_px)
    assert w.ok.all()
    np.testing.assert_allclose(w.x, xs, atol=window_bias)
    np.testing.assert_allclose(w.y, ys, atol=window_bias)
    m = mle_centroid(win, level + 3.0, noise, start_x, start_y, np.full(12, 5e3), 1.3 * sigma_px)
    assert m.ok.all()
    np.testing.assert_allclose(m.x, xs, atol=1e-4 * PIXEL)
    np.testing.assert_allclose(m.psf_sigma_px, sigma_px, rtol=1e-3)
    np.testing.assert_allclose(m.flux, 1e4, rtol=1e-3)


def test_mle_and_windowed_reach_the_bound_and_know_their_error():
    """Seeded Monte Carlo at integrated SNR 30: RMS error within 15 % of the Cramér-Rao bound
    (flux and background unknown) and the reported sigma within 15 % of the RMS error."""
    rng = np.random.default_rng(7)
    n, s, bkg, read = 400, 1.5, 100.0, 5.0
    flux = float(crb.flux_for_snr(30.0, s, bkg, read))
    xs, ys = 30 + rng.uniform(-0.5, 0.5, n), 30 + rng.uniform(-0.5, 0.5, n)
    clean = _stamps(xs, ys, np.full(n, flux), s, background=bkg, size=13)
    noisy = rng.poisson(clean.values) + rng.normal(0.0, read, clean.values.shape)
    win = Windows(noisy, clean.x0, clean.y0)
    level, noise = np.full(n, bkg), np.full(n, np.sqrt(bkg + read**2))
    start = (np.rint(xs).astype(float), np.rint(ys).astype(float))
    bound = np.sqrt(np.mean(crb.crb_sigma_px(flux, s, bkg, read, x_phase_px=xs - start[0]) ** 2))
    w = windowed_centroid(win, level, noise, *start, s, gain_e_per_adu=1.0)
    m = mle_centroid(win, level, noise, w.x, w.y, np.full(n, flux), s, fit_sigma=False,
                     gain_e_per_adu=1.0)
    for result in (w, m):
        err = np.concatenate([result.x - xs, result.y - ys])
        rms = np.sqrt(np.mean(err**2))
        assert rms < 1.15 * bound
        assert np.sqrt(np.mean(result.sigma_px**2)) == pytest.approx(rms, rel=0.15)


def test_extract_windows_marks_the_outside_and_invalid_pixels():
    data = np.arange(100.0).reshape(10, 10)
    invalid = np.zeros((10, 10), dtype=bool)
    invalid[5, 5] = True
    win = extract_windows(data, np.array([0, 5]), np.array([0, 5]), 2, invalid)
    assert win.values.shape == (2, 5, 5)
    assert np.isnan(win.values[0, :2, :]).all() and win.values[0, 2, 2] == 0.0
    assert np.isnan(win.values[1, 2, 2]) and win.values[1, 0, 0] == data[3, 3]


# --- every method through the detector --------------------------------------------------------


@pytest.fixture(scope="module")
def star_field():
    rng = np.random.default_rng(21)
    x, y = random_positions(20, (200, 200), margin=15, min_sep=20, rng=rng)
    image = render_stars((200, 200), x, y, np.full(20, 8e3), sigma_px=1.4, background=50.0,
                         read_noise=4.0, rng=rng)
    return image, x, y


@pytest.mark.parametrize(("method", "tolerance"), [
    ("peak", 0.71 * PIXEL), ("area", 0.7 * PIXEL), ("weighted", 0.15 * PIXEL),
    ("weighted-raw", 0.6 * PIXEL), ("windowed", 0.1 * PIXEL), ("mle", 0.1 * PIXEL)])
def test_every_centroider_finds_every_star(star_field, method, tolerance):
    image, x, y = star_field
    det = detect(image, centroid=method)
    assert len(det) == len(x)
    dist = np.hypot(x[:, None] - det.x[None], y[:, None] - det.y[None]).min(axis=1)
    assert dist.max() < tolerance
    assert np.all(det.sigma_px > 0)


def test_methods_rank_as_expected(star_field):
    image, x, y = star_field

    def rms(method, **kw):
        det = detect(image, centroid=method, **kw)
        return np.sqrt(np.mean(np.hypot(x[:, None] - det.x[None], y[:, None] - det.y[None])
                               .min(axis=1) ** 2))
    assert rms("mle") < 0.6 * rms("weighted")
    assert rms("windowed") < 0.6 * rms("weighted")
    assert rms("weighted") < 0.5 * rms("peak")
    assert rms("mle", psf_sigma_px=1.4) == pytest.approx(rms("mle"), rel=0.1)
    assert set(CENTROIDERS) == {"peak", "area", "weighted", "weighted-raw", "windowed", "mle"}


def test_details_carry_magnitude_width_and_shape(star_field):
    image, _, _ = star_field
    details = StarDetector(centroid="mle", mag_zero_point=25.0).detect_details(image)
    det = details.detections
    np.testing.assert_allclose(details.mag, 25.0 - 2.5 * np.log10(det.flux))
    np.testing.assert_allclose(details.psf_sigma_px, 1.4, rtol=0.05)
    np.testing.assert_allclose(det.flux, 8e3, rtol=0.05)
    assert np.all(details.major_px >= details.minor_px)
    assert details.centroid == "mle" and details.k_sigma == 5.0
    records = details.as_records()
    assert len(records) == len(det) and {"x", "y", "flux", "sigma_px", "mag"} <= set(records[0])
