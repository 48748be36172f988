"""Seeded synthetic star lists with a known attitude for the tests of the matchers on the pair
directory (angle pivot, triangles, n-vertex), and the checks those tests share."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from startrack import Camera, Status
from startrack.catalog import load_catalog
from startrack.frames import angle_between, attitude_error, boresight, random_rotations
from startrack.identify._field_stars import field_stars
from startrack.identify._pair_database import PairSettings, load_pair_database
from startrack.units import ARCSEC

CAMERA = Camera.from_fov(1024, 1024, 15.0)
PDB = load_pair_database(PairSettings(fov_deg=math.ceil(CAMERA.fov_diagonal_deg)))
PIXEL_ANGLE = CAMERA.pixel_scale_arcsec * ARCSEC
"""One pixel as an angle (radians)."""


@dataclass(frozen=True)
class StarList:
    """Centroids brightest first, the HIP number of each (-1 for a false star), the true attitude."""

    x: np.ndarray
    y: np.ndarray
    hip: np.ndarray
    truth: Rotation


def star_list(seed: int, sigma_px: float = 0.3, max_mag: float = 6.5, max_stars: int = 30) -> StarList:
    """Catalog stars (V <= max_mag, J2000) seen at a random attitude, with centroid noise, the
    second-brightest star missing and a false star put first (brightest)."""
    rng = np.random.default_rng(seed)
    truth = random_rotations(rng=rng)
    stars = field_stars(max_mag, 2000.0)
    v_cam = truth.apply(stars.vectors)
    front = np.flatnonzero(v_cam[:, 2] > 0.5)
    x, y = CAMERA.vector_to_pixel(v_cam[front])
    x, y = x + rng.normal(0, sigma_px, x.shape), y + rng.normal(0, sigma_px, y.shape)
    inside = np.flatnonzero(CAMERA.in_image(x, y))
    keep = np.delete(inside, 1)  # the second-brightest star is missing
    hip = load_catalog().hip[stars.rows[front[keep]]]
    false_x, false_y = rng.uniform(0, 1023, 2)
    return StarList(np.concatenate([[false_x], x[keep]])[:max_stars], np.concatenate([[false_y], y[keep]])[:max_stars],
                    np.concatenate([[-1], hip])[:max_stars].astype(np.int64), truth)


def mirrored(stars: StarList) -> tuple[np.ndarray, np.ndarray]:
    """The list seen in a mirror (x -> width - 1 - x)."""
    return CAMERA.width - 1 - stars.x, stars.y


def random_false_stars(seed: int, n: int = 30) -> tuple[np.ndarray, np.ndarray]:
    """A list of only false stars, uniform over the image."""
    rng = np.random.default_rng(seed)
    return rng.uniform(0, CAMERA.width - 1, n), rng.uniform(0, CAMERA.height - 1, n)


def check_identified(outcome, stars: StarList) -> None:
    """The matcher found the truth: every matched star has its own HIP (the false star is not
    matched), at least 6 stars are matched, the candidate's boresight is within 1 px of the true
    one and its roll within a few px (as angles; a pattern of a few close stars fixes the roll
    poorly), and the attitude refitted on all matched stars is within 3 px (mostly roll, whose
    error from ~10 stars with 0.3 px noise is about 1 px)."""
    assert outcome.status is Status.OK, outcome.reason
    cand = outcome.candidate
    assert len(cand.image_index) >= 6
    np.testing.assert_array_equal(load_catalog().hip[cand.catalog_rows], stars.hip[cand.image_index])
    assert angle_between(boresight(cand.rot_cam_from_icrs), boresight(stars.truth)) < 1 * PIXEL_ANGLE
    assert attitude_error(stars.truth, cand.rot_cam_from_icrs) < 8 * PIXEL_ANGLE
    observed = CAMERA.pixel_to_vector(stars.x[cand.image_index], stars.y[cand.image_index])
    refit, _ = Rotation.align_vectors(observed, load_catalog().take(cand.catalog_rows).vectors(2000.0))
    assert attitude_error(stars.truth, refit) < 3 * PIXEL_ANGLE


def check_refused(outcome) -> None:
    """No candidate: the list is a mirror image or has no real stars."""
    assert outcome.candidate is None
    assert outcome.status in (Status.NO_MATCH, Status.TIMEOUT)
