"""The last stage of every lost-in-space solve: fit the verified candidate to all stars.

A matcher verifies a candidate on the few stars of its pattern and their neighbours. This module
fits the attitude (and the focal length when it is not known) to the matched stars, re-matches
every image star to the catalog stars the fit predicts, and repeats until the matches settle
(seed 000 §1.23: the identification is confirmed and refined on all stars in the field).

A candidate can carry a wrong association or two (a false star that happened to fall within
the verification radius, or a real star paired with a neighbour). With a free focal length and a
handful of stars, the least-squares fit bends to it: the residuals of the right stars grow as
much as the wrong one's, and the bent solution no longer predicts the rest of the field, so the
re-match cannot add the stars that would expose it. :func:`settle_matches` therefore asks of
every matched star where the fit to the *other* stars puts it (its deleted residual,
:func:`.refine.leave_one_out_residuals`); a star that those would not have matched (farther than
:data:`REMATCH_RADIUS_PX`) is dropped and the fit settled again, up to :data:`MAX_LEFT_OUT` times.

A solve runs this stage once, on a few dozen stars, so its cost is numpy's per-call overhead: the
fits work on rotation matrices (:func:`.refine.fit_pose`) and the re-match only hands the
nearest-star match the predicted stars in image cells that an image star reaches (:class:`_Reach`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from .candidate import Candidate
from .field_stars import FieldStars
from .refine import fit_pose, leave_one_out_residuals
from .verify import match_nearest

MAX_REFINE_ROUNDS = 4
"""Fit / re-match rounds after verification (usually two: the second changes nothing)."""

REMATCH_RADIUS_PX = 3.0
"""After verification, every image star within this distance of a predicted star is matched."""

MIN_STARS_FOR_K1 = 12
K1_FOCAL_SPAN = 0.1
"""When the focal length is searched over a range wider than 10 % (an uncalibrated camera), the
final fit also estimates the radial distortion k1 if at least MIN_STARS_FOR_K1 stars are
matched: the lenses of photographs are rarely calibrated. A ``fov_deg`` (+-3 %) fits the focal
length only."""

BLEND_PX = 0.5
"""Catalog stars closer than this (pixels) to a brighter catalog star are not matched separately."""

FIELD_MARGIN = 1.1
"""Catalog stars within this many half-diagonals of the candidate's boresight take part in the
re-match (the refinement moves the boresight and focal length by far less than the margin)."""

SETTLED_PX = 0.05
"""Once a re-fit moves no star by more than this, re-matching cannot change the matches (bar a
star within 0.05 px of the re-match radius) and the loop stops."""

MAX_LEFT_OUT = 3
"""Wrong associations removed one at a time, at most this many (a candidate verified with a false
match probability below 1e-6 rarely carries more)."""

MIN_STARS_TO_CHECK = 5
"""Leaving one star out needs enough stars left to fit attitude and focal length and to judge."""


@dataclass(frozen=True)
class FinalFit:
    """The settled fit: attitude (rotation matrix (3, 3) taking ICRS to camera vectors), camera,
    matched image indices (K,), their catalog rows (K,), the rows' ICRS unit vectors (K, 3) at the
    solve epoch and the pixel residuals (K,)."""

    matrix_cam_from_icrs: NDArray[np.float64]
    camera: Camera
    image_index: NDArray[np.int64]
    catalog_rows: NDArray[np.int64]
    ref_icrs: NDArray[np.float64]
    residual_px: NDArray[np.float64]

    @cached_property
    def rot_cam_from_icrs(self) -> Rotation:
        """The attitude as a Rotation."""
        return Rotation.from_matrix(self.matrix_cam_from_icrs)


def visible_near(stars: FieldStars, boresight: NDArray, radius_rad: float, focal_px: float) -> NDArray[np.int64]:
    """Indices (into ``stars``, brightest first) of the catalog stars within ``radius_rad`` of the
    boresight (ICRS unit vector (3,)) that the image shows as their own spot.

    A catalog star closer than :data:`BLEND_PX` (at the focal length ``focal_px``, pixels) to a
    brighter one is left out: in the image the pair is one spot, named after its brighter star.
    """
    near = np.sort(stars.near(boresight, radius_rad))  # field stars are stored brightest first
    return near[stars.brighter_neighbour_rad[near] >= BLEND_PX / focal_px]


CELL_PX = 16.0
"""Side (pixels) of the image cells with which the re-match skips predicted stars far from every image star."""


@dataclass(frozen=True)
class _Reach:
    """The image cells (squares of side ``cell_px`` from the image corner) holding a point within
    ``radius_px`` of an image star, marked (rows, cols) once per solve.

    A predicted catalog star in an unmarked cell is farther than the radius from every image
    star, so it cannot be matched: leaving it out before :func:`.verify.match_nearest` changes
    no match and keeps the distance table small (a wide field predicts thousands of stars).
    """

    marked: NDArray[np.bool_]
    cell_px: float
    radius_px: float

    @classmethod
    def around(cls, x: NDArray, y: NDArray, width: int, height: int, radius_px: float) -> _Reach:
        """The cells within ``radius_px`` of the image stars (x, y: (N,) px) of a width x height image."""
        reach = radius_px + 1e-6  # a hair more, against rounding
        cell = max(CELL_PX, 2.0 * reach)  # so that a star reaches at most two cells along each axis
        shape = (int(height // cell) + 1, int(width // cell) + 1)
        sides = np.array([0.5 - reach, 0.5 + reach])[:, None, None]  # from the image corner, either side
        cells = ((np.array([x, y]) + sides) / cell).astype(np.intp)  # (2 sides, 2 axes, N)
        cells = np.minimum(np.maximum(cells, 0), np.array([[shape[1] - 1], [shape[0] - 1]]))
        marked = np.zeros(shape, dtype=bool)
        marked[cells[:, None, 1], cells[None, :, 0]] = True  # each star's cells, from every pair of sides
        return cls(marked, cell, radius_px)

    def holds(self, px: NDArray, py: NDArray) -> NDArray[np.bool_]:
        """Whether each position (px, py: (M,) px, inside the image) lies in a marked cell."""
        return self.marked[((py + 0.5) / self.cell_px).astype(np.intp), ((px + 0.5) / self.cell_px).astype(np.intp)]


@dataclass(frozen=True)
class _Field:
    """What stays fixed while a candidate settles: image stars (N,) px and the cells they reach,
    the field's catalog stars (those of :func:`visible_near`: rows (S,) and ICRS unit vectors
    (S, 3)) and whether the focal length is free."""

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    reach: _Reach
    near_rows: NDArray[np.int64]
    near_vectors: NDArray[np.float64]
    fit_focal: bool


def rematch(field: _Field, matrix_cam_from_icrs: NDArray,
            camera: Camera) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """Match every image star to its nearest predicted catalog star of the field within the
    radius of ``field.reach``, for an attitude matrix (3, 3) taking ICRS to camera vectors:
    image index (K,), catalog row (K,) and the row's ICRS unit vector (K, 3)."""
    px, py = camera.vector_to_pixel(field.near_vectors @ matrix_cam_from_icrs.T)
    inside = np.flatnonzero(camera.in_image(px, py))
    near_i = inside[field.reach.holds(px[inside], py[inside])]  # the few that can match
    img_i, cat_i = match_nearest(field.x, field.y, px[near_i], py[near_i], field.reach.radius_px)
    near_i = near_i[cat_i]
    return img_i, field.near_rows[near_i], field.near_vectors[near_i]


def _turn_rad(matrix_a: NDArray, matrix_b: NDArray) -> float:
    """Angle (radians) of the rotation between two attitude matrices (3, 3): atan2 of the sine
    (from the antisymmetric part of ``A B^T``) and the cosine (from its trace), precise at any angle."""
    (d00, d01, d02), (d10, d11, d12), (d20, d21, d22) = (matrix_a @ matrix_b.T).tolist()
    return math.atan2(0.5 * math.hypot(d21 - d12, d02 - d20, d10 - d01), 0.5 * (d00 + d11 + d22 - 1.0))


def _pose_shift_px(matrix_a: NDArray, cam_a: Camera, matrix_b: NDArray, cam_b: Camera) -> float:
    """Largest shift (pixels) of an image point between two attitudes (matrices (3, 3)) and focal lengths."""
    half_diagonal_px = 0.5 * math.hypot(cam_a.width, cam_a.height)
    focal_change = abs(cam_a.fx / cam_b.fx - 1.0)
    turn = _turn_rad(matrix_a, matrix_b)
    return turn * cam_b.fx * (1.0 + (half_diagonal_px / cam_b.fx) ** 2) + focal_change * half_diagonal_px


def _settle(field: _Field, matrix: NDArray, camera: Camera, img: NDArray, rows: NDArray, ref: NDArray) -> FinalFit:
    """Fit, re-match all stars, and repeat until the matches (or the pose) stop changing.
    ``ref`` (K, 3) are the ICRS unit vectors of the catalog rows (K,) matched to the image stars (K,)."""
    for round_ in range(MAX_REFINE_ROUNDS):
        before = (matrix, camera)
        matrix, camera, res = fit_pose(matrix, camera, ref, field.x[img], field.y[img], fit_focal=field.fit_focal)
        if round_ == MAX_REFINE_ROUNDS - 1 or (round_ > 0 and _pose_shift_px(*before, matrix, camera) < SETTLED_PX):
            break
        new_img, new_rows, new_ref = rematch(field, matrix, camera)
        unchanged = np.array_equal(new_img, img) and np.array_equal(new_rows, rows)
        if unchanged or new_img.size < img.size:
            break
        img, rows, ref = new_img, new_rows, new_ref
    return FinalFit(matrix, camera, img, rows, ref, res)


def _without_worst(field: _Field, fit: FinalFit) -> FinalFit | None:
    """The fit settled again without the star the others' fit puts farthest from its match, if
    that is beyond the re-match radius (the others would not have matched it); else None."""
    img = fit.image_index
    deleted = leave_one_out_residuals(fit.matrix_cam_from_icrs, fit.camera, fit.ref_icrs, field.x[img],
                                      field.y[img], fit_focal=field.fit_focal)
    deleted = np.where(np.isfinite(deleted), deleted, 0.0)  # a star the fit cannot do without is kept
    worst = int(np.argmax(deleted))
    if deleted[worst] <= REMATCH_RADIUS_PX:
        return None
    keep = np.arange(img.size) != worst
    return _settle(field, fit.matrix_cam_from_icrs, fit.camera, img[keep], fit.catalog_rows[keep], fit.ref_icrs[keep])


def settle_matches(x: NDArray, y: NDArray, stars: FieldStars, cand: Candidate,
                   focal_range: tuple[float, float] | None) -> FinalFit:
    """Fit a verified candidate to every star it explains, dropping a wrong association.

    Parameters
    ----------
    x, y : ndarray, shape (N,)
        Image stars (pixels, brightest first), as the matcher saw them.
    stars : FieldStars
        Catalog stars at the solve epoch.
    cand : Candidate
        The matcher's verified candidate.
    focal_range : (float, float) or None
        Focal lengths searched (pixels), or None when the camera is calibrated (focal length
        fixed). The focal length is fitted when a range is given; k1 as well when the range is
        wider than :data:`K1_FOCAL_SPAN` and at least :data:`MIN_STARS_FOR_K1` stars match.

    Returns
    -------
    FinalFit
    """
    fit_focal = focal_range is not None
    fit_k1 = fit_focal and focal_range[1] > focal_range[0] * (1 + K1_FOCAL_SPAN)
    matrix, camera = cand.rot_cam_from_icrs.as_matrix(), cand.camera
    radius_rad = FIELD_MARGIN * math.radians(camera.fov_diagonal_deg) / 2.0
    near = visible_near(stars, matrix[2], radius_rad, camera.fx)
    reach = _Reach.around(x, y, camera.width, camera.height, REMATCH_RADIUS_PX)
    field = _Field(x, y, reach, stars.rows[near], stars.vectors[near], fit_focal)
    rows = cand.catalog_rows
    fit = _settle(field, matrix, camera, cand.image_index, rows, stars.vectors_of(rows))
    for _ in range(MAX_LEFT_OUT):
        better = _without_worst(field, fit) if fit.image_index.size >= MIN_STARS_TO_CHECK else None
        if better is None:
            break
        fit = better
    if fit_k1 and fit.image_index.size >= MIN_STARS_FOR_K1:  # lens distortion last, on the settled matches
        img = fit.image_index
        matrix, camera, res = fit_pose(fit.matrix_cam_from_icrs, fit.camera, fit.ref_icrs, x[img], y[img],
                                       fit_focal=True, fit_k1=True)
        fit = FinalFit(matrix, camera, img, fit.catalog_rows, fit.ref_icrs, res)
    return fit
