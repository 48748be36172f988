"""Detector read-out: each noise term, its switch, quantisation, saturation, reproducibility."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from startrack.errors import InvalidInputError
from startrack.simulate import Detector, NoiseModel, Optics, Sensor, read_out

SHAPE = (200, 200)
OFF = NoiseModel(shot=False, dark=False, read=False, bias=False, quantize=False, saturate=False)


def sensor(**detector) -> Sensor:
    settings = {"gain_e_per_adu": 2.0, "read_noise_e": 8.0, "dark_current_e_s": 30.0,
                "bias_adu": 50.0, "full_well_e": 5e4, "bit_depth": 14}
    settings.update(detector)
    return Sensor(optics=Optics(aperture_area_m2=1e-4), detector=Detector(**settings),
                  exposure_s=2.0)


def flat(value: float) -> np.ndarray:
    return np.full(SHAPE, value)


def with_(**on) -> NoiseModel:
    return dataclasses.replace(OFF, **on)


def test_everything_off_is_signal_over_gain():
    image = read_out(flat(300.0), sensor(), noise=OFF, rng=0)
    assert image.dtype == np.float64
    np.testing.assert_array_equal(image, 150.0)


def test_ideal_keeps_the_expected_dark_background_and_bias():
    s = sensor()
    image = read_out(flat(300.0), s, background_e=40.0, noise=False)
    np.testing.assert_allclose(image, (300.0 + 40.0 + 60.0) / 2.0 + 50.0, rtol=1e-15)


def test_read_noise_alone_has_the_stated_std():
    image = read_out(flat(0.0), sensor(), noise=with_(read=True), rng=1)
    assert image.mean() == pytest.approx(0.0, abs=0.05)
    assert image.std() * 2.0 == pytest.approx(8.0, rel=0.05)


def test_shot_noise_alone_is_poisson():
    image = read_out(flat(100.0), sensor(gain_e_per_adu=1.0), background_e=20.0,
                     noise=with_(shot=True, dark=True), rng=2)
    mean = 100.0 + 20.0 + 60.0
    assert image.mean() == pytest.approx(mean, rel=0.01)
    assert image.var() == pytest.approx(mean, rel=0.03)
    np.testing.assert_array_equal(image, np.round(image))  # whole electrons


@pytest.mark.parametrize("term, variance_e2", [("shot", 400.0 + 60.0), ("read", 64.0)])
def test_switching_a_term_off_removes_its_variance(term, variance_e2):
    all_random = with_(shot=True, read=True, dark=True)
    without = dataclasses.replace(all_random, **{term: False})
    full = read_out(flat(400.0), sensor(), noise=all_random, rng=3).var() * 4.0
    reduced = read_out(flat(400.0), sensor(), noise=without, rng=3).var() * 4.0
    assert full - reduced == pytest.approx(variance_e2, rel=0.1)


def test_dark_switch_removes_the_dark_level():
    s = sensor()
    with_dark = read_out(flat(0.0), s, noise=with_(dark=True))
    np.testing.assert_allclose(with_dark, s.dark_e / 2.0)
    np.testing.assert_array_equal(read_out(flat(0.0), s, noise=OFF), 0.0)


def test_bias_switch_adds_the_bias():
    np.testing.assert_array_equal(read_out(flat(0.0), sensor(), noise=with_(bias=True)), 50.0)


def test_quantisation_rounds_to_nearest_and_returns_uint16():
    # Huffman 2006 §3.2.4 example at 117 e-/ADU: 0-58 e- read as 0, 59-"176" e- as 1 ADU (the exact
    # boundary is 1.5 * 117 = 175.5 e-)
    s = sensor(gain_e_per_adu=117.0, bit_depth=10)
    signal = np.array([[0.0, 58.0, 59.0, 175.0, 176.0]])
    image = read_out(signal, s, noise=with_(quantize=True))
    assert image.dtype == np.uint16
    np.testing.assert_array_equal(image, [[0, 0, 1, 1, 2]])


def test_quantised_values_are_clipped_to_the_adc_range():
    s = sensor(bit_depth=8, read_noise_e=50.0)
    image = read_out(np.array([[0.0, 1e4]]), s, noise=with_(quantize=True, read=True), rng=4)
    assert image.min() >= 0 and image.max() == 255


def test_saturation_clips_at_full_well_and_at_max_adu():
    s = sensor(gain_e_per_adu=1.0, bit_depth=16, full_well_e=3e4)
    huge = np.array([[1e5, 100.0]])
    np.testing.assert_array_equal(read_out(huge, s, noise=with_(saturate=True)), [[3e4, 100.0]])
    np.testing.assert_array_equal(read_out(huge, s, noise=OFF), [[1e5, 100.0]])
    s8 = sensor(gain_e_per_adu=100.0, bit_depth=8, full_well_e=1e6)
    assert read_out(huge, s8, noise=with_(saturate=True)).max() == 255.0


def test_same_seed_is_bit_identical_and_another_seed_differs():
    s = sensor()
    a = read_out(flat(200.0), s, rng=7)
    b = read_out(flat(200.0), s, rng=np.random.default_rng(7))
    c = read_out(flat(200.0), s, rng=8)
    assert a.dtype == np.uint16
    np.testing.assert_array_equal(a, b)
    assert np.any(a != c)


@pytest.mark.parametrize("kwargs", [
    {"signal_e": -np.ones((3, 3))},
    {"signal_e": np.ones(3)},
    {"signal_e": np.ones((3, 3)), "background_e": -1.0},
    {"signal_e": np.ones((3, 3)), "background_e": np.ones((2, 2))},
    {"signal_e": np.ones((3, 3)), "noise": "yes"},
])
def test_misuse_raises(kwargs):
    with pytest.raises(InvalidInputError):
        read_out(sensor=sensor(), **kwargs)


@pytest.mark.parametrize("exposure_s, prnu", [(1e300, 0.0), (1e16, 0.0), (2.0, 1e300)])
def test_a_charge_beyond_the_poisson_draw_names_the_settings(exposure_s, prnu):
    # a sky of 1e3 e-/s: 1e19 e- at 1e16 s, past the 1e18 e- a pixel may expect; a PRNU of 1e300 scales it too
    s = dataclasses.replace(sensor(prnu_rms=prnu), exposure_s=exposure_s)
    with pytest.raises(InvalidInputError, match="a pixel expects .* electrons in the exposure, more than the 1e"
                                               "\\+18 the simulator can draw: shorten the exposure"):
        read_out(np.zeros(SHAPE), s, background_e=1e3 * exposure_s, rng=1)


def test_a_sky_too_bright_for_a_table_is_drawn_pixel_by_pixel():
    # 1e16 e-: a read-out table would span 2.6e9 charges (27 GB); the pixels are drawn one by one instead
    image = read_out(np.zeros((4, 4)), sensor(), background_e=1e16, noise=with_(shot=True, quantize=True), rng=1)
    assert image.dtype == np.uint16 and np.all(image == 2**14 - 1)
