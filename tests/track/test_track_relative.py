"""Frame-to-frame relative attitude without a catalog (Huffman 2006 triangle and rate matches)."""

import numpy as np
from scipy.spatial.transform import Rotation

from startrack import Status
from startrack.catalog import load_catalog
from startrack.frames import random_rotations
from startrack.track import rate_match, triangle_match
from startrack.units import ARCSEC, DEG

NOISE = 5 * ARCSEC
"""Per-axis noise of each star vector; a pair's difference then scatters by about 10 arcsec."""


def _errors_arcsec(truth, found):
    """Pointing error (of the boresight) and total error; about the boresight a 15 deg field of
    ~20 stars with 10 arcsec pair noise leaves a roll uncertainty of some 30 arcsec."""
    z = np.array([0.0, 0.0, 1.0])
    pointing = np.degrees(np.arccos(np.clip(truth.apply(z) @ found.apply(z), -1, 1))) * 3600
    return pointing, (truth * found.inv()).magnitude() / ARCSEC


def _frames(seed, rate_deg_s=(0.5, -1.0, 0.3), dt=0.5, n=25):
    """Camera vectors of the brightest stars in a 15 deg cone before and after a turn, with noise,
    a star lost and a star gained (the fields overlap but differ)."""
    rng = np.random.default_rng(seed)
    cat = load_catalog().brighter_than(6.5)
    first_att = random_rotations(None, rng)
    rate = np.radians(rate_deg_s)
    second_att = Rotation.from_rotvec(-rate * dt) * first_att

    def seen(att):
        cam = att.apply(cat.vectors())
        idx = np.flatnonzero(cam[:, 2] > np.cos(7.5 * DEG))
        idx = idx[np.argsort(cat.v_mag[idx])][:n]
        noisy = cam[idx] + rng.normal(0, NOISE, (idx.size, 3))
        return noisy / np.linalg.norm(noisy, axis=1, keepdims=True)

    return seen(first_att), seen(second_att), second_att * first_att.inv(), rate, dt


def test_triangle_match_recovers_the_relative_attitude():
    first, second, truth, _, _ = _frames(1)
    found = triangle_match(first, second, tol_rad=4 * NOISE)
    assert found.status is Status.OK
    pointing, total = _errors_arcsec(truth, found.rot_cam2_from_cam1)
    assert pointing < 5 and total < 90
    assert found.index1.size >= 10


def test_triangle_match_refuses_a_mirrored_second_frame():
    first, second, _, _, _ = _frames(2)
    mirrored = second * np.array([-1.0, 1.0, 1.0])
    assert triangle_match(first, mirrored, tol_rad=4 * NOISE).status is not Status.OK


def test_rate_match_with_the_known_rate():
    first, second, truth, rate, dt = _frames(3)
    found = rate_match(first, second, rate, dt, tol_rad=30 * ARCSEC)
    assert found.status is Status.OK
    pointing, total = _errors_arcsec(truth, found.rot_cam2_from_cam1)
    assert pointing < 5 and total < 90
    wrong = rate_match(first, second, -5 * rate, dt, tol_rad=30 * ARCSEC)
    assert wrong.status is Status.NO_MATCH
