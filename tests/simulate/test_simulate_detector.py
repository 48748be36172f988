"""Detector effects: the exact read-out table, fixed pattern (PRNU, DSNU, hot and dead pixels),
blooming, and every noise source switched off one at a time."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.stats import chi2, poisson

from startrack.simulate import Detector, NoiseModel, Optics, Sensor, pixel_maps, read_out
from startrack.simulate._detector import bloom
from startrack.simulate._noise import readout_table, sample_table

SHAPE = (200, 200)


def sensor(**detector) -> Sensor:
    settings = {"gain_e_per_adu": 1.7, "read_noise_e": 3.0, "dark_current_e_s": 10.0, "bias_adu": 40.0,
                "full_well_e": 3e4, "bit_depth": 12}
    settings.update(detector)
    return Sensor(optics=Optics(aperture_area_m2=1e-4), detector=Detector(**settings), exposure_s=0.5)


def pixel_by_pixel(s: Sensor, level: float, rng: int) -> np.ndarray:
    """Read-out of a flat level through steps 2-6 on every pixel: a background that differs by
    1e-9 e- in one corner is not uniform, so the table is not used."""
    background = np.full(SHAPE, level)
    background[0, 0] += 1e-9
    return read_out(np.zeros(SHAPE), s, background_e=background, rng=rng)


def histogram_chi2_p(a: np.ndarray, b: np.ndarray) -> float:
    """p-value that two samples of integers come from one distribution (bins with >= 10 counts)."""
    lo = int(min(a.min(), b.min()))
    ha = np.bincount(a.ravel().astype(np.int64) - lo)
    hb = np.bincount(b.ravel().astype(np.int64) - lo, minlength=ha.size)
    ha = np.pad(ha, (0, hb.size - ha.size))
    keep = (ha + hb) >= 10
    ha, hb = ha[keep], hb[keep]
    expected_a = (ha + hb) * a.size / (a.size + b.size)
    expected_b = (ha + hb) * b.size / (a.size + b.size)
    stat = ((ha - expected_a) ** 2 / expected_a + (hb - expected_b) ** 2 / expected_b).sum()
    return float(chi2.sf(stat, keep.sum() - 1))


@pytest.mark.parametrize("level", [0.0, 0.7, 7.5, 180.0])
def test_table_path_draws_the_same_distribution_as_pixel_by_pixel(level):
    """The fast path (one table draw per pixel) against steps 2-6 on every pixel."""
    s = sensor()
    fast = read_out(np.zeros(SHAPE), s, background_e=level, rng=1)
    slow = pixel_by_pixel(s, level, 2)
    assert fast.dtype == slow.dtype == np.uint16
    assert histogram_chi2_p(fast, slow) > 1e-3
    mean = (level + s.dark_e) / 1.7 + 40.0
    var = (level + s.dark_e + 9.0) / 1.7**2 + 1 / 12
    assert fast.mean() == pytest.approx(mean, abs=5 * np.sqrt(var / fast.size))
    assert fast.var() == pytest.approx(var, rel=0.05)


def test_read_out_table_is_a_distribution_and_sampling_follows_it():
    values, cdf, guide = readout_table(12.0, sensor().detector, NoiseModel())
    assert np.all(np.diff(values.astype(int)) > 0) and np.all(np.diff(cdf) >= 0) and cdf[-1] == 1.0
    draws = sample_table(cdf, guide, 400_000, np.random.default_rng(3))
    counts = np.bincount(draws, minlength=cdf.size)
    probs = np.diff(np.concatenate([[0.0], cdf]))
    big = probs * draws.size > 20
    stat = ((counts[big] - probs[big] * draws.size) ** 2 / (probs[big] * draws.size)).sum()
    assert chi2.sf(stat, big.sum() - 1) > 1e-3


def test_saturated_levels_stay_exact():
    """A level near the full well: the table clips the charge like the pixel path."""
    s = sensor(full_well_e=100.0, read_noise_e=0.0, gain_e_per_adu=1.0, bias_adu=0.0, dark_current_e_s=0.0)
    fast = read_out(np.zeros(SHAPE), s, background_e=98.0, rng=4)
    slow = pixel_by_pixel(s, 98.0, 5)
    assert fast.max() == 100 and histogram_chi2_p(fast, slow) > 1e-3
    assert np.mean(fast == 100) == pytest.approx(poisson.sf(99, 98.0), abs=0.01)


def test_pixel_maps_are_seeded_per_sensor_and_have_the_stated_statistics():
    det = sensor(prnu_rms=0.02, dsnu_rms=0.3, hot_pixel_fraction=0.01, dead_pixel_fraction=0.005).detector
    shape = (500, 500)
    maps = pixel_maps(det, shape)
    assert pixel_maps(det, shape) is maps  # cached: every frame sees the same sensor
    other = pixel_maps(dataclasses.replace(det, pixel_map_seed=1), shape)
    assert not np.array_equal(maps.response, other.response)
    assert maps.response.std() == pytest.approx(0.02, rel=0.05)
    assert maps.dark_scale.std() == pytest.approx(0.3, rel=0.05)
    n = maps.hot.size
    for mask, fraction in ((maps.hot, 0.01), (maps.dead, 0.005)):
        assert abs(mask.sum() - fraction * n) < 5 * np.sqrt(fraction * n)
    assert not np.any(maps.hot & maps.dead)
    assert not maps.response.flags.writeable


def test_bloom_spills_along_the_column_and_conserves_charge():
    column = np.array([0.0, 10.0, 50.0, 380.0, 40.0, 0.0, 0.0])[:, None] * np.ones((1, 2))
    column[:, 1] = [0.0, 0.0, 0.0, 90.0, 0.0, 0.0, 0.0]  # nothing to spill
    before = column.copy()
    bloom(column, 100.0)
    assert column.max() <= 100.0
    assert column[:, 0].sum() == pytest.approx(before[:, 0].sum())
    np.testing.assert_allclose(column[:, 0], [0.0, 100.0, 100.0, 100.0, 100.0, 80.0, 0.0])
    np.testing.assert_array_equal(column[:, 1], before[:, 1])


def test_bloom_loses_only_the_charge_that_leaves_the_array():
    column = np.array([[500.0], [0.0], [0.0]])
    bloom(column, 100.0)
    np.testing.assert_allclose(column[:, 0], [100.0, 100.0, 100.0])  # 200 e- left through the top


# ---------------------------------------------------------------- every source can be switched off
def star_image(shape=SHAPE, peak=2e3):
    y, x = np.indices(shape)
    return peak * np.exp(-((x - 100.3) ** 2 + (y - 99.6) ** 2) / (2 * 2.0**2))


EFFECTS = {"prnu_rms": 0.05, "dsnu_rms": 0.5, "hot_pixel_fraction": 0.002, "dead_pixel_fraction": 0.002}
ALL = NoiseModel(blooming=True)


def render(model: NoiseModel, signal=None, **detector) -> np.ndarray:
    s = sensor(**{**EFFECTS, **detector})
    signal = np.full(SHAPE, 50.0) if signal is None else signal
    return read_out(signal, s, background_e=30.0, noise=model, rng=7).astype(float)


@pytest.mark.parametrize("term", ["shot", "read"])
def test_random_terms_off_remove_their_variance(term):
    base = dataclasses.replace(NoiseModel.ideal(), shot=True, read=True, quantize=False)
    with_term = render(base).var()
    without = render(dataclasses.replace(base, **{term: False})).var()
    expected = {"shot": (50.0 + 30.0 + 5.0) / 1.7**2, "read": 9.0 / 1.7**2}[term]
    assert with_term - without == pytest.approx(expected, rel=0.15)


@pytest.mark.parametrize("term", ["prnu", "dsnu", "hot_pixels", "dead_pixels"])
def test_fixed_pattern_terms_off_remove_their_pattern(term):
    ideal = NoiseModel.ideal()
    only = dataclasses.replace(ideal, **{term: True})
    pattern = render(only) - render(ideal)
    assert np.abs(pattern).max() > 0.5
    maps = pixel_maps(sensor(**EFFECTS).detector, SHAPE)
    where = {"hot_pixels": maps.hot, "dead_pixels": maps.dead}.get(term)
    if where is not None:
        assert np.all(pattern[~where] == 0) and np.all(pattern[where] != 0)
    np.testing.assert_array_equal(render(ideal), render(dataclasses.replace(only, **{term: False})))


@pytest.mark.parametrize(("term", "offset_adu"), [("dark", 5.0 / 1.7), ("bias", 40.0), ("background", 30.0 / 1.7)])
def test_level_terms_off_remove_their_level(term, offset_adu):
    ideal = NoiseModel.ideal()
    difference = render(ideal, **{k: 0.0 for k in EFFECTS}) - render(
        dataclasses.replace(ideal, **{term: False}), **{k: 0.0 for k in EFFECTS})
    np.testing.assert_allclose(difference, offset_adu)


def test_quantisation_off_leaves_fractions_and_on_gives_integers():
    assert np.any(render(NoiseModel(quantize=False)) % 1 != 0)
    on = read_out(np.full(SHAPE, 50.0), sensor(), rng=1)
    assert on.dtype == np.uint16


def test_saturation_and_blooming_switches():
    bright = star_image(peak=1e6)
    clip = render(dataclasses.replace(NoiseModel.ideal(), saturate=True, quantize=True), bright)
    free = render(NoiseModel.ideal(), bright)
    bled = render(dataclasses.replace(NoiseModel.ideal(), saturate=True, blooming=True, quantize=True), bright)
    top = (3e4 + 5.0 + 30.0 * 1.05) / 1.7 + 40
    assert clip.max() <= top and free.max() > 1e5
    column = bled[:, 100] - clip[:, 100]
    assert column[40:60].min() > 1e3  # the bleed trail runs far beyond the PSF (sigma 2 px)
    assert np.all(np.abs((bled - clip)[:, :90]) < 1e-6)  # and stays in the saturated columns
