"""The simulator against its analytic companions: SNR, photometry, limiting magnitude, smear-limited
rate (Samaan 2002 Table 1) and the expected number of stars in the field."""

from __future__ import annotations

import math

import numpy as np
import pytest

from startrack import get_preset
from startrack.camera import Camera
from startrack.simulate import (
    Detector,
    NoiseModel,
    Optics,
    Sensor,
    expected_star_count,
    limiting_magnitude,
    max_rate_rad_s,
    peak_snr,
    random_attitude,
    render_stars,
    simulate_frame,
    star_snr,
)
from startrack.simulate._snr import box_fraction, noise_per_pixel_e2
from startrack.units import DEG, PIXEL

N_FRAMES = 1000
BOX = 7
SKY_E = 20.0
CENTRES = [(11.0, 11.0), (36.0, 11.0), (11.0, 36.0), (36.0, 36.0)]  # pixel centres, 25 px apart


@pytest.fixture(scope="module")
def sensor() -> Sensor:
    """Gain 2 e-/ADU (quantisation noise 0.58 e- rms), read 6 e-, dark 40 e-/s, bias 100, t = 0.5 s."""
    return Sensor(optics=Optics(aperture_area_m2=1e-4, psf_sigma_px=1.2),
                  detector=Detector(quantum_efficiency=0.5, gain_e_per_adu=2.0, read_noise_e=6.0,
                                    dark_current_e_s=40.0, bias_adu=100.0, full_well_e=2e5, bit_depth=16),
                  exposure_s=0.5)


@pytest.fixture(scope="module")
def box_sums(sensor):
    """Background-subtracted box sums (e-) of 4 stars in each of 1,000 seeded 48 x 48 frames."""
    camera = Camera.from_fov(48, 48, 1.0)
    rot = random_attitude(4)
    x, y = np.array(CENTRES).T
    vectors = rot.inv().apply(camera.pixel_to_vector(x, y))
    mag = limiting_magnitude(20.0, sensor, box_px=BOX, background_e=SKY_E)
    det = sensor.detector
    level_adu = (SKY_E + sensor.dark_e) / det.gain_e_per_adu + det.bias_adu
    half = BOX // 2
    rng = np.random.default_rng(2024)
    sums = []
    for _ in range(N_FRAMES):
        image = render_stars(camera, rot, vectors, np.full(4, mag), np.arange(4), sensor=sensor,
                             background_e=SKY_E, rng=rng).image.astype(float)
        sums += [(image[int(cy) - half:int(cy) + half + 1, int(cx) - half:int(cx) + half + 1] - level_adu).sum()
                 for cx, cy in CENTRES]
    return mag, np.array(sums) * det.gain_e_per_adu


def test_measured_snr_of_simulated_stars_matches_the_analytic_snr(sensor, box_sums):
    mag, sums = box_sums
    measured = sums.mean() / sums.std(ddof=1)
    analytic = float(star_snr(mag, sensor, box_px=BOX, background_e=SKY_E))
    assert analytic == pytest.approx(20.0, rel=1e-9)  # limiting_magnitude inverts star_snr
    assert measured == pytest.approx(analytic, rel=0.05)


def test_mean_box_flux_is_the_expected_electrons_within_the_shot_noise_bound(sensor, box_sums):
    mag, sums = box_sums
    expected = float(sensor.electrons(mag)) * box_fraction(sensor.psf_sigma_px, BOX)
    assert abs(sums.mean() - expected) < 4.0 * sums.std(ddof=1) / math.sqrt(sums.size)


def test_total_flux_of_a_star_is_its_expected_electrons_within_shot_noise(sensor):
    camera = Camera.from_fov(40, 40, 1.0)
    rot = random_attitude(9)
    v = rot.inv().apply(camera.pixel_to_vector(np.array([19.3]), np.array([20.6])))
    shot_only = NoiseModel(shot=True, dark=False, read=False, bias=False, quantize=False, saturate=False)
    rng = np.random.default_rng(5)
    totals = np.array([render_stars(camera, rot, v, [9.0], [1], sensor=sensor, noise=shot_only,
                                    rng=rng).image.sum() for _ in range(300)]) * sensor.detector.gain_e_per_adu
    expected = float(sensor.electrons(9.0))
    assert np.all(np.abs(totals - expected) < 5.0 * math.sqrt(expected))
    assert abs(totals.mean() - expected) < 4.0 * math.sqrt(expected / totals.size)
    assert totals.var(ddof=1) == pytest.approx(expected, rel=0.25)  # Poisson: variance = mean


def test_every_noise_term_enters_the_snr(sensor):
    full = float(star_snr(8.0, sensor, box_px=BOX, background_e=SKY_E))
    for term in ("shot", "dark", "read", "quantize", "background"):
        fewer = float(star_snr(8.0, sensor, box_px=BOX, background_e=SKY_E, noise=NoiseModel(**{term: False})))
        assert fewer > full, term
    var = noise_per_pixel_e2(sensor, SKY_E)
    assert var == pytest.approx(SKY_E + sensor.dark_e + 36.0 + 4.0 / 12.0)


def test_peak_snr_is_seed_000_eq_3_18_with_a_pixel_integrated_peak(sensor):
    electrons = float(sensor.electrons(7.0))
    sigma_noise = math.sqrt(noise_per_pixel_e2(sensor, SKY_E))
    peak = electrons * box_fraction(sensor.psf_sigma_px, 1)
    assert float(peak_snr(7.0, sensor, background_e=SKY_E)) == pytest.approx(peak / sigma_noise, rel=1e-12)
    # the pixel-integrated peak is a little below the sampled one, eNum / (2 pi sigma^2)
    sampled = electrons / (2 * math.pi * sensor.psf_sigma_px**2)
    assert 0.9 * sampled < peak < sampled


def test_limiting_magnitude_is_fainter_for_a_lower_snr_and_a_longer_exposure(sensor):
    assert limiting_magnitude(5.0, sensor) > limiting_magnitude(10.0, sensor)
    assert limiting_magnitude(5.0, sensor.with_exposure(2.0)) > limiting_magnitude(5.0, sensor)
    for snr in (3.0, 10.0, 100.0):
        assert float(star_snr(limiting_magnitude(snr, sensor), sensor)) == pytest.approx(snr, rel=1e-9)


@pytest.mark.parametrize(("exposure_ms", "printed_deg_s"), [(10, 0.156), (20, 0.078), (30, 0.052), (50, 0.0313)])
def test_seed_004_table_1_maximum_rate_for_negligible_smear(exposure_ms, printed_deg_s):
    """StarNav I, 512 x 512 px, f = 58 mm with the 15.84 um pitch of an 8 deg FOV (the notes'
    erratum: Table 1 implies 8 deg, not the 7 deg of the text), 1/10 px of smear."""
    camera = get_preset("starnav-i")
    assert camera.fov_deg == pytest.approx(8.0, abs=0.01)
    half_last_digit = 0.5 * 10.0 ** -len(str(printed_deg_s).split(".")[1])
    for cam, ifov in ((camera, "center"), (Camera.from_fov(512, 512, 8.0), "mean")):
        rate = max_rate_rad_s(cam, exposure_ms * 1e-3, 0.1, ifov=ifov) / DEG
        assert abs(rate - printed_deg_s) <= half_last_digit + 1e-6
    seven_deg = Camera.from_fov(512, 512, 7.0)
    assert max_rate_rad_s(seven_deg, exposure_ms * 1e-3, ifov="mean") / DEG < 0.9 * printed_deg_s


def test_a_star_at_the_maximum_rate_smears_by_the_fraction_of_a_pixel():
    camera = get_preset("starnav-i")
    sensor = Sensor(optics=Optics(aperture_area_m2=1e-4, psf_sigma_px=1.0), exposure_s=0.02)
    rot = random_attitude(12)
    v = rot.inv().apply(camera.pixel_to_vector(np.array([camera.cx]), np.array([camera.cy])))
    rate = max_rate_rad_s(camera, sensor.exposure_s, 0.1)
    sim = render_stars(camera, rot, v, [3.0], [1], sensor=sensor, noise=False, rate_rad_s=(0.0, rate, 0.0))
    assert float(sim.truth.streak_length_px[0]) == pytest.approx(0.1, abs=1e-6 * PIXEL)


def test_simulated_star_counts_agree_with_the_expected_count():
    camera = Camera.from_fov(64, 48, 20.0)
    counts = [int(simulate_frame(camera, random_attitude(seed), max_mag=6.0, noise=False).truth.inside().sum())
              for seed in range(400)]
    expected = expected_star_count(camera, 6.0)
    assert 20 < expected < 40
    assert np.mean(counts) == pytest.approx(expected, rel=0.06)
