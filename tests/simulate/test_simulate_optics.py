"""Optics and light: the Airy PSF, field curvature, vignetting, star colour and the sky background."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.special import j0, j1

from startrack.camera import Camera
from startrack.errors import InvalidInputError
from startrack.simulate import (
    PASSBANDS,
    NoiseModel,
    Optics,
    Passband,
    SkyBackground,
    random_attitude,
    render_stars,
    simulate_frame,
    zodiacal_mag_arcsec2,
)
from startrack.simulate._background import S10_MAG_ARCSEC2, ecliptic_latitude
from startrack.simulate._optics import airy_intensity, airy_stamps, psf_sigma_px, star_illumination
from startrack.units import DEG, PIXEL

EXPECTED_ONLY = NoiseModel(shot=False, dark=False, read=False, bias=False, quantize=False, saturate=False,
                           background=False)


def stars_at(camera, rot, x, y):
    return rot.inv().apply(camera.pixel_to_vector(np.asarray(x, float), np.asarray(y, float)))


def test_airy_intensity_has_unit_integral_and_its_first_zero_where_asked():
    r0 = 2.5
    r = np.linspace(0.0, 400.0, 400_001)
    assert np.trapezoid(airy_intensity(r, r0) * 2 * np.pi * r, r) == pytest.approx(1.0, abs=2e-3)
    assert airy_intensity(np.array([r0]), r0)[0] < 1e-12 * airy_intensity(np.array([0.0]), r0)[0]


def test_airy_stamp_holds_the_encircled_energy_and_is_centred():
    """Encircled energy of the Airy pattern: 1 - J0(u)^2 - J1(u)^2 at u = pi r / w (Rayleigh)."""
    r0 = 2.0
    w = r0 / 1.2196698912665045
    stamps = airy_stamps(np.array([0.3]), np.array([-0.2]), r0, radius_px=30, oversample=7)[0]
    k = np.arange(-30, 31)
    inside_disc = np.hypot(k[None, :] - 0.3, k[:, None] + 0.2) <= 10.0
    u = np.pi * 10.0 / w
    assert stamps[inside_disc].sum() == pytest.approx(1 - j0(u) ** 2 - j1(u) ** 2, abs=0.01)
    cols = (stamps.sum(axis=0) * k).sum() / stamps.sum()
    rows = (stamps.sum(axis=1) * k).sum() / stamps.sum()
    assert cols == pytest.approx(0.3, abs=0.01 * PIXEL) and rows == pytest.approx(-0.2, abs=0.01 * PIXEL)


def test_airy_frame_renders_stars_where_the_truth_says(plain_sensor):
    camera = Camera.from_fov(120, 100, 4.0)
    sensor = dataclasses.replace(plain_sensor, optics=dataclasses.replace(plain_sensor.optics, psf="airy",
                                                                          airy_first_zero_px=1.8))
    rot = random_attitude(3)
    sim = render_stars(camera, rot, stars_at(camera, rot, [60.4], [50.3]), [3.0], [1], sensor=sensor,
                       noise=EXPECTED_ONLY)
    image = sim.image * sensor.detector.gain_e_per_adu
    assert 0.93 < image.sum() / sim.truth.electrons[0] < 1.0  # the far rings beyond 5 r0 are lost
    rows, cols = np.indices(image.shape)
    assert (cols * image).sum() / image.sum() == pytest.approx(60.4, abs=0.02 * PIXEL)


def test_field_curvature_widens_the_psf_towards_the_corners():
    camera = Camera.from_fov(200, 100, 10.0)
    optics = Optics(aperture_area_m2=1e-4, psf_sigma_px=1.0, field_curvature=0.5)
    sigma = psf_sigma_px(camera, optics, np.array([camera.cx, -0.5]), np.array([camera.cy, -0.5]))
    np.testing.assert_allclose(sigma, [1.0, 1.5])


def test_natural_vignetting_dims_stars_by_cos_theta_and_the_sky_by_cos4(plain_sensor):
    camera = Camera.from_fov(300, 300, 60.0)
    optics = dataclasses.replace(plain_sensor.optics, natural_vignetting=True, vignetting_edge=0.2)
    sensor = dataclasses.replace(plain_sensor, optics=optics)
    rot = random_attitude(4)
    x, y = np.array([camera.cx, 20.0]), np.array([camera.cy, 30.0])
    sim = render_stars(camera, rot, stars_at(camera, rot, x, y), [3.0, 3.0], [1, 2], sensor=sensor, noise=False)
    cos_theta = camera.pixel_to_vector(20.0, 30.0)[2]
    r2 = np.hypot(20.0 - camera.cx, 30.0 - camera.cy) ** 2 / (2 * 150.0**2)
    ratio = sim.truth.electrons[1] / sim.truth.electrons[0]
    assert ratio == pytest.approx(cos_theta * (1 - 0.2 * r2), rel=1e-9)
    assert float(star_illumination(camera, optics, camera.cx, camera.cy)) == pytest.approx(1.0)
    sky = SkyBackground(mag_arcsec2=21.0).electrons(camera, sensor)
    centre = SkyBackground(mag_arcsec2=21.0).sky_electrons_px(camera, sensor)
    assert sky[30, 20] / centre == pytest.approx(cos_theta**4 * (1 - 0.2 * r2), rel=1e-6)


def test_v_band_colour_factor_is_one_and_silicon_sees_red_stars_brighter():
    assert np.allclose(PASSBANDS["v"].colour_factor([-0.3, 0.0, 0.65, 1.5, np.nan]), 1.0, atol=2e-3)
    silicon = PASSBANDS["silicon"].colour_factor(np.array([0.0, 0.65, 1.5]))
    assert np.all(np.diff(silicon) > 0)  # redder stars put more of their light in the red and near IR
    assert 3.0 < silicon[1] < 6.0  # a solar-type star: several times the V-band photons


def test_sensor_passband_scales_star_electrons_by_the_colour_factor(plain_sensor):
    red = dataclasses.replace(plain_sensor, passband=PASSBANDS["silicon"])
    factor = red.electrons(5.0, 1.2) / plain_sensor.electrons(5.0, 1.2)
    assert float(factor) == pytest.approx(float(PASSBANDS["silicon"].colour_factor(1.2)))
    assert float(plain_sensor.electrons(5.0, 1.2)) == float(plain_sensor.electrons(5.0))


def test_bad_passbands_are_refused():
    with pytest.raises(InvalidInputError):
        Passband("x", (500.0, 400.0), (1.0, 1.0))
    with pytest.raises(InvalidInputError):
        Passband("x", (400.0, 500.0), (1.0, 2.0))


def test_zodiacal_model_spans_the_dark_space_sky():
    assert S10_MAG_ARCSEC2 == pytest.approx(27.78, abs=0.01)
    pole, plane = zodiacal_mag_arcsec2([90 * DEG, 0.0])
    assert pole == pytest.approx(23.3, abs=0.05) and plane == pytest.approx(21.7, abs=0.05)
    north_ecliptic_pole = np.array([0.0, -math.sin(23.4392911 * DEG), math.cos(23.4392911 * DEG)])
    assert ecliptic_latitude(north_ecliptic_pole) == pytest.approx(math.pi / 2)
    assert ecliptic_latitude(np.array([1.0, 0.0, 0.0])) == pytest.approx(0.0, abs=1e-12)  # the equinox


def test_sky_background_electrons_follow_the_surface_brightness(plain_sensor):
    camera = Camera.from_fov(100, 100, 5.0)
    pixel_arcsec2 = (3600 * 180 / math.pi) ** 2 / (camera.fx * camera.fy)
    bg = SkyBackground(mag_arcsec2=20.0, stray_e_s_px=3.0)
    expected = float(plain_sensor.electrons(20.0)) * pixel_arcsec2 + 3.0 * plain_sensor.exposure_s
    assert bg.electrons(camera, plain_sensor) == pytest.approx(expected, rel=1e-12)
    sloped = SkyBackground(mag_arcsec2=None, stray_e_s_px=10.0, stray_gradient=0.5).electrons(camera, plain_sensor)
    assert sloped[50, 99] > sloped[50, 0] and sloped.mean() == pytest.approx(10.0, rel=1e-3)


def test_steep_diagonal_stray_light_stops_at_zero(plain_sensor):
    """A gradient of 0.9 along 45 deg would be negative in the far corner (the corners lie
    sqrt(2) half-sides from the centre); the light is zero there, and the frame renders."""
    camera = Camera.from_fov(100, 100, 5.0)
    light = SkyBackground(mag_arcsec2=None, stray_e_s_px=10.0, stray_gradient=0.9,
                          stray_direction_deg=45.0).electrons(camera, plain_sensor)
    per_exposure = 10.0 * plain_sensor.exposure_s  # electrons per pixel at the centre
    assert light.min() == 0.0 and light[0, 0] == 0.0
    assert light[99, 99] == pytest.approx(per_exposure * (1 + 0.9 * np.hypot(49.5, 49.5) / 50), rel=1e-12)
    frame = simulate_frame(camera, random_attitude(rng=1), sensor=plain_sensor, rng=1,
                           sky_background=SkyBackground(stray_e_s_px=2000.0, stray_gradient=0.8,
                                                        stray_direction_deg=45.0))
    assert np.isfinite(frame.image).all()
