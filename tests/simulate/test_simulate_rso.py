"""Orbits (two-body + J2), the Earth's shadow, Sun and Moon, satellites in the image, bright-body flags."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from astropy.time import Time

from startrack.camera import Camera
from startrack.errors import InvalidInputError
from startrack.frames import angle_between, rotation_from_radec_roll, vector_to_radec
from startrack.simulate import (
    RSO,
    FrameTiming,
    KeplerElements,
    NoiseModel,
    Orbit,
    OrbitalScene,
    in_earth_shadow,
    render_stars,
    sun_moon_km,
)
from startrack.simulate._orbits import J2_EARTH, MU_EARTH_KM3_S2, R_EARTH_KM
from startrack.simulate._rso import SUN_V_MAG, Snapshot
from startrack.units import DEG, PIXEL

EPOCH = Time("2026-03-01T00:00:00", scale="utc")
EXPECTED_ONLY = NoiseModel(shot=False, dark=False, read=False, bias=False, quantize=False, saturate=False,
                           background=False)


def raan(r, v):
    h = np.cross(r, v)
    return math.atan2(h[0], -h[1])


def test_two_body_orbit_closes_after_one_period():
    el = KeplerElements.from_degrees(7200.0, 0.05, 40.0, 30.0, 60.0, 10.0)
    orbit = Orbit.from_elements(EPOCH, el, j2=False)
    r, v = orbit.states([el.period_s, -el.period_s])
    np.testing.assert_allclose(r, [orbit.r_km, orbit.r_km], atol=1e-3)
    np.testing.assert_allclose(v, [orbit.v_km_s, orbit.v_km_s], atol=1e-6)
    assert np.linalg.norm(orbit.r_km) == pytest.approx(7200.0 * (1 - 0.05**2) / (1 + 0.05 * math.cos(10 * DEG)))


def test_repeated_and_unsorted_times_give_the_states_of_each_time():
    """Repeated times raised "t_eval not properly sorted" from solve_ivp before."""
    orbit = Orbit.from_elements(EPOCH, KeplerElements.from_degrees(7000.0, 0.01, 50.0, 10.0, 20.0, 30.0))
    times = np.array([300.0, -120.0, 300.0, 0.0, 60.0, -120.0, 60.0])
    r, v = orbit.states(times)
    r_once, v_once = orbit.states(np.array([300.0, -120.0, 0.0, 60.0]))
    for k, t in enumerate(times):
        j = [300.0, -120.0, 0.0, 60.0].index(t)
        np.testing.assert_allclose(r[k], r_once[j], atol=1e-6)   # km
        np.testing.assert_allclose(v[k], v_once[j], atol=1e-9)   # km/s


def test_j2_regresses_the_node_at_the_textbook_rate():
    a, inc = 7000.0, 50.0 * DEG
    el = KeplerElements(a, 0.0, inc, 0.0, 0.0, 0.0)
    orbit = Orbit.from_elements(EPOCH, el)
    t = 10 * el.period_s
    r, v = orbit.states([t])
    n = math.sqrt(MU_EARTH_KM3_S2 / a**3)
    expected = -1.5 * n * J2_EARTH * (R_EARTH_KM / a) ** 2 * math.cos(inc) * t
    assert raan(r[0], v[0]) - raan(orbit.r_km, orbit.v_km_s) == pytest.approx(expected, rel=0.03)


def test_earth_shadow_is_the_cylinder_behind_the_earth():
    sun = np.array([1.5e8, 0.0, 0.0])
    points = np.array([[-7000.0, 0.0, 0.0], [-7000.0, 7000.0, 0.0], [7000.0, 0.0, 0.0], [-50000.0, 6000.0, 0.0]])
    np.testing.assert_array_equal(in_earth_shadow(points, sun), [True, False, False, True])


def test_sun_and_moon_from_the_builtin_ephemeris():
    """Against the Astronomical Almanac's low-precision solar coordinates (0.01 deg), precessed back
    from the equinox of date to J2000 (1.397 deg per century in ecliptic longitude)."""
    times = EPOCH + np.array([0.0, 100.0, 200.0]) * 86400 * __import__("astropy.units", fromlist=["s"]).s
    sun, moon = sun_moon_km(times)
    for k, jd in enumerate(times.tt.jd):
        n = jd - 2451545.0
        g = math.radians(357.528 + 0.9856003 * n)
        lam = math.radians(280.460 + 0.9856474 * n + 1.915 * math.sin(g) + 0.020 * math.sin(2 * g)
                           - 1.397 * n / 36525.0)
        eps = math.radians(23.4393)
        ref = np.array([math.cos(lam), math.cos(eps) * math.sin(lam), math.sin(eps) * math.sin(lam)])
        assert angle_between(sun[k], ref) < 0.05 * DEG
        assert 1.46e8 < np.linalg.norm(sun[k]) < 1.53e8
        assert 3.5e5 < np.linalg.norm(moon[k]) < 4.1e5


def test_lambertian_magnitude_at_full_phase():
    obs = Orbit.from_elements(EPOCH, KeplerElements(7000.0, 0.0, 0.0, 0.0, 0.0, 0.0))
    rso = RSO(Orbit.from_elements(EPOCH, KeplerElements(8000.0, 0.0, 0.0, 0.0, 0.0, 0.0)), radius_m=2.0,
              albedo=0.3)
    au = 149_597_870.7
    snap = Snapshot(EPOCH, np.array([9000.0, 0, 0]), np.zeros(3), np.array([[8000.0, 0, 0]]), np.zeros((1, 3)),
                    sun=np.array([au, 0.0, 0.0]),
                    moon=np.array([0.0, 4e5, 0.0]), scene=OrbitalScene(obs, (rso,)))
    # the Sun behind the observer: phase angle 0, range 1000 km, the Sun (au - 8000 km) away
    expected = SUN_V_MAG - 2.5 * math.log10(2 / 3 * 0.3 * (2.0 / 1e6) ** 2 / ((au - 8000.0) / au) ** 2)
    assert snap.rso_magnitudes()[0] == pytest.approx(expected, abs=1e-6)


@pytest.fixture(scope="module")
def chase():
    """Observer in a 700 km circular orbit and a satellite 3 deg ahead in a slightly higher one."""
    obs = Orbit.from_elements(EPOCH, KeplerElements.from_degrees(7078.0, 0.0, 51.6, 20.0, 0.0, 0.0))
    target = Orbit.from_elements(EPOCH, KeplerElements.from_degrees(7100.0, 0.0, 51.6, 20.0, 0.0, 3.0))
    return OrbitalScene(obs, (RSO(target, ident=25544, mag=3.0),))


def test_a_satellite_lands_where_the_camera_points_and_streaks_with_its_motion(chase, plain_sensor):
    camera = Camera.from_fov(256, 256, 10.0)
    snap = chase.snapshots(EPOCH)[0]
    los = snap.rso_r[0] - snap.observer_r
    ra, dec = vector_to_radec(los)
    rot = rotation_from_radec_roll(ra, dec, 0.3)
    sensor = plain_sensor.with_exposure(0.2)
    timing = FrameTiming(epoch=EPOCH)
    sim = render_stars(camera, rot, np.zeros((0, 3)), [], np.zeros(0, dtype=int), sensor=sensor,
                       noise=EXPECTED_ONLY, timing=timing, orbital=chase)
    rsos = sim.truth.rsos
    assert rsos.lit[0] and rsos.rendered[0] and rsos.ids[0] == 25544
    assert rsos.x[0] == pytest.approx(camera.cx, abs=0.2 * PIXEL)  # light time: a few arcsec
    assert rsos.y[0] == pytest.approx(camera.cy, abs=0.2 * PIXEL)
    length = math.hypot(rsos.x_end[0] - rsos.x_start[0], rsos.y_end[0] - rsos.y_start[0])
    assert 0.05 < length < 5.0  # a slow drift across the still star field
    assert (rsos.x_start[0] + rsos.x_end[0]) / 2 == pytest.approx(rsos.x[0], abs=0.01 * PIXEL)
    image = sim.image * sensor.detector.gain_e_per_adu
    assert image.sum() == pytest.approx(rsos.electrons[0], rel=1e-5)
    assert rsos.electrons[0] == pytest.approx(float(sensor.electrons(3.0, 0.65)))
    flags = sim.truth.bright_bodies
    assert flags is not None and sim.truth.time_mid == EPOCH


def test_a_satellite_in_the_earth_shadow_is_not_rendered(chase, plain_sensor):
    snap = chase.snapshots(EPOCH)[0]
    shadow = dataclasses.replace(snap, sun=-snap.rso_r[0] / np.linalg.norm(snap.rso_r[0]) * 1.5e8)
    camera = Camera.from_fov(128, 128, 10.0)
    ra, dec = vector_to_radec(snap.rso_r[0] - snap.observer_r)
    sim = render_stars(camera, rotation_from_radec_roll(ra, dec, 0.0), np.zeros((0, 3)), [],
                       np.zeros(0, dtype=int), sensor=plain_sensor, noise=EXPECTED_ONLY, orbital=shadow)
    assert not sim.truth.rsos.lit[0] and not sim.truth.rsos.rendered[0]
    assert sim.truth.rsos.mag[0] == np.inf and np.all(sim.image == 0)


def test_bright_body_flags(chase):
    snap = chase.snapshots(EPOCH)[0]
    camera = Camera.from_fov(512, 512, 20.0)
    at_sun = snap.bright_bodies(snap.sun / np.linalg.norm(snap.sun), camera)
    assert at_sun.sun_in_fov and at_sun.sun_near and at_sun.sun_edge_deg < 0 and at_sun.corrupted
    nadir = -snap.observer_r / np.linalg.norm(snap.observer_r)
    down = snap.bright_bodies(nadir, camera)
    assert down.earth_in_fov and down.earth_edge_deg < 0
    zenith = snap.bright_bodies(-nadir, camera)
    assert not zenith.earth_in_fov and zenith.earth_edge_deg == pytest.approx(
        180.0 - math.degrees(math.asin(R_EARTH_KM / np.linalg.norm(snap.observer_r))), abs=1e-9)


def test_satellites_need_an_absolute_time(chase, plain_sensor):
    camera = Camera.from_fov(64, 64, 10.0)
    with pytest.raises(InvalidInputError, match="absolute time"):
        render_stars(camera, rotation_from_radec_roll(0.0, 0.0, 0.0), np.zeros((0, 3)), [], np.zeros(0, dtype=int),
                     sensor=plain_sensor, orbital=chase)
    with pytest.raises(InvalidInputError):
        KeplerElements(6000.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # inside the Earth
