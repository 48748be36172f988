"""startrack.frames: sky directions, stable angles, the RA / Dec / roll attitude format."""

from __future__ import annotations

from pathlib import Path

import mpmath
import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.io import fits
from astropy.wcs import WCS
from scipy.spatial.transform import Rotation

from startrack.camera import Camera
from startrack.errors import InvalidInputError
from startrack.frames import (
    angle_between,
    attitude_error,
    boresight,
    normalize,
    radec_roll_from_rotation,
    radec_to_vector,
    random_rotations,
    rotation_from_radec_roll,
    vector_to_radec,
)
from startrack.units import ARCSEC, DEG, PIXEL

RNG_SEED = 31415
EXACT = 1e-12  # rad: round-off level for rotations built from trigonometric functions
RAD_PER_ARCSEC_PX = 206264.806247


def _wrap_deg(a):
    """Angle difference folded into [-180, 180) degrees."""
    return (np.asarray(a) + 180.0) % 360.0 - 180.0


def _random_sky(n, rng):
    ra = rng.uniform(0.0, 2 * np.pi, n)
    dec = np.arcsin(rng.uniform(-1.0, 1.0, n))
    return ra, dec


# --- directions ------------------------------------------------------------------------------
def test_radec_to_vector_matches_astropy():
    ra, dec = _random_sky(500, np.random.default_rng(RNG_SEED))
    ours = radec_to_vector(ra, dec)
    ref = SkyCoord(ra * u.rad, dec * u.rad, frame="icrs").cartesian.xyz.value.T
    np.testing.assert_allclose(ours, ref, atol=1e-15)
    assert ours.shape == (500, 3)


def test_vector_to_radec_matches_astropy_and_ranges():
    rng = np.random.default_rng(RNG_SEED + 1)
    v = rng.normal(size=(500, 3)) * rng.uniform(0.1, 10.0, size=(500, 1))  # not unit length
    ra, dec = vector_to_radec(v)
    ref = SkyCoord(x=v[:, 0], y=v[:, 1], z=v[:, 2], representation_type="cartesian",
                   frame="icrs")
    ref.representation_type = "spherical"
    angle = angle_between(radec_to_vector(ra, dec), v)
    assert np.max(angle) < 1e-15
    np.testing.assert_allclose(ra, ref.ra.rad, atol=1e-14)
    np.testing.assert_allclose(dec, ref.dec.rad, atol=1e-14)
    assert np.all((ra >= 0) & (ra < 2 * np.pi))
    assert np.all(np.abs(dec) <= np.pi / 2)


def test_vector_to_radec_wrap_and_poles():
    ra, _ = vector_to_radec([1.0, -1e-12, 0.0])  # just below RA = 0: wraps to just below 2 pi
    assert 2 * np.pi - 2e-12 < ra < 2 * np.pi
    ra, dec = vector_to_radec([[0.0, 0.0, 2.0], [0.0, 0.0, -1.0]])
    np.testing.assert_array_equal(ra, [0.0, 0.0])
    np.testing.assert_array_equal(dec, [np.pi / 2, -np.pi / 2])


# --- angle between vectors -------------------------------------------------------------------
def _mp_angle(u_vec, v_vec):
    """Exact (50-digit) angle between the float vectors as given."""
    with mpmath.workdps(50):
        a = [mpmath.mpf(float(c)) for c in u_vec]
        b = [mpmath.mpf(float(c)) for c in v_vec]
        cross = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
        return float(mpmath.atan2(mpmath.sqrt(sum(c * c for c in cross)), dot))


def _pairs_at(angle, n, rng):
    """n random vector pairs (float64) separated by about ``angle``."""
    u_vec = normalize(rng.normal(size=(n, 3)))
    w = normalize(np.cross(u_vec, rng.normal(size=(n, 3))))
    return u_vec, np.cos(angle) * u_vec + np.sin(angle) * w


def test_angle_between_analytic_tiny_and_near_pi():
    tiny = 1e-10
    assert angle_between([1.0, 0.0, 0.0], [1.0, tiny, 0.0]) == pytest.approx(np.arctan(tiny),
                                                                              rel=1e-15)
    near_pi = angle_between([1.0, 0.0, 0.0], [-1.0, tiny, 0.0])
    assert abs(near_pi - (np.pi - np.arctan(tiny))) < 1e-15
    assert angle_between([0, 0, 3.0], [0, 0, 5.0]) == 0.0
    assert angle_between([0, 0, 1.0], [0, 0, -2.0]) == pytest.approx(np.pi, abs=0)


@pytest.mark.parametrize("angle", [1e-10, 1e-7, 1 * ARCSEC, 0.5, np.pi / 2, np.pi - 1e-7,
                                   np.pi - 1e-10])
def test_angle_between_vs_high_precision(angle):
    rng = np.random.default_rng(RNG_SEED + 2)
    u_vec, v_vec = _pairs_at(angle, 40, rng)
    ours = angle_between(u_vec, v_vec)
    exact = np.array([_mp_angle(a, b) for a, b in zip(u_vec, v_vec, strict=True)])
    assert np.max(np.abs(ours - exact)) < 1e-15  # rad: a few ulp of the inputs
    # the test can fail: arccos(dot) misses by far more at the ends of the range
    if angle < 1e-6 or angle > np.pi - 1e-6:
        naive = np.arccos(np.clip(np.sum(u_vec * v_vec, axis=-1), -1, 1))
        assert np.max(np.abs(naive - exact)) > 1e-12


def test_angle_between_broadcasts_and_scales():
    rng = np.random.default_rng(RNG_SEED + 3)
    u_vec, v_vec = _pairs_at(0.3, 10, rng)
    np.testing.assert_allclose(angle_between(3.0 * u_vec, 0.2 * v_vec), 0.3, atol=1e-15)
    assert angle_between(u_vec[0], v_vec).shape == (10,)


# --- RA / Dec / roll -------------------------------------------------------------------------
def _edge_attitudes(rng):
    """RA / Dec / roll sets that include the poles, RA = 0 and RA just below / at 360 deg."""
    ra, dec = _random_sky(300, rng)
    roll = rng.uniform(0.0, 2 * np.pi, 300)
    edge_ra = np.array([0.0, 2 * np.pi - 1e-12, 2 * np.pi, 1.0, 0.0, 3.0, np.pi])
    edge_dec = np.array([0.3, -0.4, 0.1, np.pi / 2, -np.pi / 2, np.pi / 2 - 1e-9, 0.0])
    edge_roll = np.array([0.0, 2 * np.pi - 1e-12, 1.0, 0.0, 5.0, np.pi, 2 * np.pi])
    return (np.concatenate([ra, edge_ra]), np.concatenate([dec, edge_dec]),
            np.concatenate([roll, edge_roll]))


def test_rotation_round_trip_over_random_and_edge_attitudes():
    ra, dec, roll = _edge_attitudes(np.random.default_rng(RNG_SEED + 4))
    rot = rotation_from_radec_roll(ra, dec, roll)
    assert len(rot) == len(ra)
    ra2, dec2, roll2 = radec_roll_from_rotation(rot)
    back = rotation_from_radec_roll(ra2, dec2, roll2)
    assert np.max(attitude_error(rot, back)) < EXACT
    assert np.all((ra2 >= 0) & (ra2 <= 2 * np.pi) & (roll2 >= 0) & (roll2 <= 2 * np.pi))
    # away from the poles the angles themselves come back (RA and roll modulo 2 pi)
    ok = np.abs(dec) < np.pi / 2 - 1e-6
    np.testing.assert_allclose(dec2, dec, atol=EXACT)
    assert np.max(np.abs(_wrap_deg((ra2 - ra)[ok] / DEG))) * DEG < 1e-9
    assert np.max(np.abs(_wrap_deg((roll2 - roll)[ok] / DEG))) * DEG < 1e-9


def test_ra_and_roll_stay_below_two_pi():
    ra, _ = vector_to_radec([1.0, -1e-17, 0.0])
    assert 0.0 <= ra < 2 * np.pi
    ra, dec, roll = _edge_attitudes(np.random.default_rng(RNG_SEED + 4))
    ra2, _, roll2 = radec_roll_from_rotation(rotation_from_radec_roll(ra, dec, roll))
    assert np.all((ra2 >= 0) & (ra2 < 2 * np.pi) & (roll2 >= 0) & (roll2 < 2 * np.pi))


def test_rotation_round_trip_from_uniform_rotations():
    rot = random_rotations(400, rng=RNG_SEED + 5)
    back = rotation_from_radec_roll(*radec_roll_from_rotation(rot))
    assert np.max(attitude_error(rot, back)) < EXACT


def test_scalar_input_gives_single_rotation():
    rot = rotation_from_radec_roll(0.1, 0.2, 0.3)
    assert rot.single
    ra, dec, roll = radec_roll_from_rotation(rot)
    assert np.ndim(ra) == 0
    assert (float(ra), float(dec), float(roll)) == pytest.approx((0.1, 0.2, 0.3), abs=EXACT)


def test_boresight_is_at_ra_dec():
    ra, dec, roll = _edge_attitudes(np.random.default_rng(RNG_SEED + 6))
    rot = rotation_from_radec_roll(ra, dec, roll)
    target = radec_to_vector(ra, dec)
    assert np.max(angle_between(boresight(rot), target)) < EXACT
    np.testing.assert_allclose(rot.apply(target), np.tile([0.0, 0.0, 1.0], (len(ra), 1)),
                               atol=EXACT)


def _north_east_reference(ra, dec):
    """Local north and east from the derivatives of the direction (independent of frames.py)."""
    north = np.array([-np.sin(dec) * np.cos(ra), -np.sin(dec) * np.sin(ra), np.cos(dec)])
    east = np.array([-np.sin(ra), np.cos(ra), 0.0])
    return north, east


@pytest.mark.parametrize(("ra_deg", "dec_deg"), [(0.0, 0.0), (83.6, 22.0), (250.0, -60.0),
                                                 (359.9, 89.0), (10.0, -89.5)])
def test_roll_zero_puts_north_up_and_west_right(ra_deg, dec_deg):
    ra, dec = ra_deg * DEG, dec_deg * DEG
    icrs_from_cam = rotation_from_radec_roll(ra, dec, 0.0).inv()
    north, east = _north_east_reference(ra, dec)
    np.testing.assert_allclose(icrs_from_cam.apply([0.0, -1.0, 0.0]), north, atol=EXACT)  # up
    np.testing.assert_allclose(icrs_from_cam.apply([1.0, 0.0, 0.0]), -east, atol=EXACT)  # right


def test_stars_north_and_east_of_centre_land_up_and_left():
    """On an un-mirrored sky photo with roll 0, north is up (smaller y) and east is left."""
    ra, dec = 120.0 * DEG, 35.0 * DEG
    rot = rotation_from_radec_roll(ra, dec, 0.0)
    cam = Camera.from_fov(640, 480, 10.0)
    stars = radec_to_vector([ra, ra, ra + 1.0 * DEG], [dec, dec + 1.0 * DEG, dec])
    x, y = cam.vector_to_pixel(rot.apply(stars))
    assert (x[0], y[0]) == pytest.approx((cam.cx, cam.cy), abs=1e-9)
    assert y[1] < cam.cy - 50 and abs(x[1] - cam.cx) < 1e-6  # north: up
    assert x[2] < cam.cx - 30 and abs(y[2] - cam.cy) < 1.0  # east: left


@pytest.mark.parametrize("roll_deg", [0.0, 30.0, 90.0, 180.0, 271.5, 359.0])
def test_roll_is_minus_position_angle_of_up(roll_deg):
    ra, dec = 40.0 * DEG, -25.0 * DEG
    up_cam = np.array([0.0, -0.01, 1.0])  # a point just above the image centre
    up_icrs = rotation_from_radec_roll(ra, dec, roll_deg * DEG).inv().apply(up_cam)
    up_ra, up_dec = vector_to_radec(up_icrs)
    centre = SkyCoord(ra * u.rad, dec * u.rad, frame="icrs")
    pa = centre.position_angle(SkyCoord(up_ra * u.rad, up_dec * u.rad, frame="icrs")).deg
    assert abs(_wrap_deg(pa + roll_deg)) < 1e-7


def test_random_rotations_is_seeded_and_checks_n():
    a = random_rotations(5, rng=3)
    b = random_rotations(5, rng=np.random.default_rng(3))
    assert np.max(attitude_error(a, b)) == 0.0
    assert isinstance(random_rotations(rng=1), Rotation)
    with pytest.raises(InvalidInputError, match="n must be"):
        random_rotations(0)


# --- real data: the roll convention against astrometry.net ------------------------------------
def _truth_wcs(realdata_dir: Path, row: dict) -> WCS:
    stem = Path(row["file"]).stem
    header = fits.getheader(realdata_dir / row["set"] / "truth" / f"{stem}.wcs")
    header["NAXIS"] = 2  # the .wcs file is a header-only FITS (NAXIS = 0)
    header["NAXIS1"] = int(row["width"])
    header["NAXIS2"] = int(row["height"])
    return WCS(header)


def _solution(realdata_dir, row):
    """WCS, centre pixel, centre direction and PA of 'up' from astrometry.net's WCS."""
    wcs = _truth_wcs(realdata_dir, row)
    cx, cy = (int(row["width"]) - 1) / 2.0, (int(row["height"]) - 1) / 2.0
    # astropy's pixel_to_world takes 0-based pixel coordinates: the same as ours
    centre = wcs.pixel_to_world(cx, cy).icrs
    up = wcs.pixel_to_world(cx, cy - 10.0).icrs
    return wcs, (cx, cy), centre, centre.position_angle(up).deg


def test_truth_roll_matches_our_roll_definition(realdata_dir, truth_table):
    for row in truth_table:
        _, _, centre, pa = _solution(realdata_dir, row)
        truth_centre = SkyCoord(float(row["ra_center_deg"]), float(row["dec_center_deg"]),
                                unit="deg", frame="icrs")
        assert centre.separation(truth_centre).arcsec < 1.0, row["file"]
        assert abs(_wrap_deg(pa - float(row["pa_image_up_deg_E_of_N"]))) < 0.05, row["file"]
        roll = (-pa) % 360.0
        assert abs(_wrap_deg(roll - float(row["roll_tetra3_deg"]))) < 0.05, row["file"]
        rot = rotation_from_radec_roll(centre.ra.rad, centre.dec.rad, roll * DEG)
        _, _, our_roll = radec_roll_from_rotation(rot)
        assert abs(_wrap_deg(our_roll / DEG - float(row["roll_tetra3_deg"]))) < 0.05, row["file"]


def test_truth_cd_matrix_matches_documented_formula(realdata_dir, truth_table):
    """docs/conventions.md: for an un-mirrored image at roll r and scale s (deg/px),
    CD = s * [[-cos r, sin r], [-sin r, -cos r]]."""
    for row in truth_table:
        wcs = _truth_wcs(realdata_dir, row)
        scale = float(row["pixscale_arcsec"]) / 3600.0
        roll = float(row["roll_tetra3_deg"]) * DEG
        expected = scale * np.array([[-np.cos(roll), np.sin(roll)],
                                     [-np.sin(roll), -np.cos(roll)]])
        assert np.max(np.abs(wcs.wcs.cd - expected)) < 0.01 * scale, row["file"]


def test_truth_attitude_reprojects_the_solved_image(realdata_dir, truth_table):
    """Our attitude + a pinhole camera put the WCS sky positions and the matched catalogue stars
    back on their pixels: this catches a mirrored image or a roll of the wrong sign, which
    would miss by hundreds of pixels."""
    for row in truth_table:
        wcs, (cx, cy), centre, pa = _solution(realdata_dir, row)
        rot = rotation_from_radec_roll(centre.ra.rad, centre.dec.rad, -pa * DEG)
        width, height = int(row["width"]), int(row["height"])
        cam = Camera(width, height, fx=RAD_PER_ARCSEC_PX / float(row["pixscale_arcsec"]))
        gx, gy = (g.ravel() for g in np.meshgrid(np.linspace(0.1, 0.9, 5) * width,
                                                 np.linspace(0.1, 0.9, 5) * height))
        sky = wcs.pixel_to_world(gx, gy).icrs
        x, y = cam.vector_to_pixel(rot.apply(radec_to_vector(sky.ra.rad, sky.dec.rad)))
        radius = np.hypot(gx - cx, gy - cy)
        # allowance: lens distortion (SIP) and plate anisotropy the pinhole model leaves out
        assert np.all(np.hypot(x - gx, y - gy) < 0.03 * radius + 1.0 * PIXEL), row["file"]
        stem = Path(row["file"]).stem
        corr = fits.getdata(realdata_dir / row["set"] / "truth" / f"{stem}.corr", 1)
        stars = radec_to_vector(np.radians(corr["index_ra"]), np.radians(corr["index_dec"]))
        sx, sy = cam.vector_to_pixel(rot.apply(stars))
        miss = np.hypot(sx - (corr["field_x"] - 1.0), sy - (corr["field_y"] - 1.0))  # FITS 1-based
        assert np.median(miss) < 1.5 * PIXEL, row["file"]
