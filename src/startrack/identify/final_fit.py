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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from .candidate import Candidate
from .field_stars import FieldStars
from .refine import leave_one_out_residuals, refine_pointing
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
    """The settled fit: attitude, camera, matched image indices (K,), their catalog rows (K,),
    the rows' ICRS unit vectors (K, 3) at the solve epoch and the pixel residuals (K,)."""

    rot_cam_from_icrs: Rotation
    camera: Camera
    image_index: NDArray[np.int64]
    catalog_rows: NDArray[np.int64]
    ref_icrs: NDArray[np.float64]
    residual_px: NDArray[np.float64]


def visible_near(stars: FieldStars, boresight: NDArray, radius_rad: float, focal_px: float) -> NDArray[np.int64]:
    """Indices (into ``stars``, brightest first) of the catalog stars within ``radius_rad`` of the
    boresight (ICRS unit vector (3,)) that the image shows as their own spot.

    A catalog star closer than :data:`BLEND_PX` (at the focal length ``focal_px``, pixels) to a
    brighter one is left out: in the image the pair is one spot, named after its brighter star.
    """
    near = np.sort(stars.near(boresight, radius_rad))  # field stars are stored brightest first
    return near[stars.brighter_neighbour_rad[near] >= BLEND_PX / focal_px]


def rematch(x: NDArray, y: NDArray, stars: FieldStars, near: NDArray, rot: Rotation,
            camera: Camera, radius_px: float) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Match every image star (x, y: (N,) px) to its nearest predicted catalog star within the
    radius: (image index (K,), catalog row (K,)). ``near`` (from :func:`visible_near`) are the
    indices (into ``stars``) of the catalog stars around the field, found once per solve."""
    px, py = camera.vector_to_pixel(stars.vectors[near] @ rot.as_matrix().T)
    inside = np.flatnonzero(camera.in_image(px, py))
    img_i, cat_i = match_nearest(x, y, px[inside], py[inside], radius_px)
    return img_i, stars.rows[near[inside[cat_i]]]


def _pose_shift_px(rot_a: Rotation, cam_a: Camera, rot_b: Rotation, cam_b: Camera) -> float:
    """Largest shift (pixels) of an image point between two attitudes and focal lengths."""
    turn = float(np.linalg.norm((rot_a * rot_b.inv()).as_rotvec()))
    half_diagonal_px = 0.5 * math.hypot(cam_a.width, cam_a.height)
    focal_change = abs(cam_a.fx / cam_b.fx - 1.0)
    return turn * cam_b.fx * (1.0 + (half_diagonal_px / cam_b.fx) ** 2) + focal_change * half_diagonal_px


@dataclass(frozen=True)
class _Field:
    """What stays fixed while a candidate settles: image stars (N,) px, the field's catalog stars
    and whether the focal length is free."""

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    stars: FieldStars
    near: NDArray[np.int64]
    fit_focal: bool


def _settle(field: _Field, rot: Rotation, camera: Camera, img: NDArray, rows: NDArray) -> FinalFit:
    """Fit, re-match all stars, and repeat until the matches (or the pose) stop changing."""
    for round_ in range(MAX_REFINE_ROUNDS):
        ref = field.stars.vectors_of(rows)
        before = (rot, camera)
        rot, camera, res = refine_pointing(rot, camera, ref, field.x[img], field.y[img], fit_focal=field.fit_focal)
        if round_ == MAX_REFINE_ROUNDS - 1 or (round_ > 0 and _pose_shift_px(*before, rot, camera) < SETTLED_PX):
            break
        new_img, new_rows = rematch(field.x, field.y, field.stars, field.near, rot, camera, REMATCH_RADIUS_PX)
        unchanged = np.array_equal(new_img, img) and np.array_equal(new_rows, rows)
        if unchanged or new_img.size < img.size:
            break
        img, rows = new_img, new_rows
    return FinalFit(rot, camera, img, rows, ref, res)


def _without_worst(field: _Field, fit: FinalFit) -> FinalFit | None:
    """The fit settled again without the star the others' fit puts farthest from its match, if
    that is beyond the re-match radius (the others would not have matched it); else None."""
    img = fit.image_index
    deleted = leave_one_out_residuals(fit.rot_cam_from_icrs, fit.camera, fit.ref_icrs, field.x[img], field.y[img],
                                      fit_focal=field.fit_focal)
    deleted = np.where(np.isfinite(deleted), deleted, 0.0)  # a star the fit cannot do without is kept
    worst = int(np.argmax(deleted))
    if deleted[worst] <= REMATCH_RADIUS_PX:
        return None
    keep = np.arange(img.size) != worst
    return _settle(field, fit.rot_cam_from_icrs, fit.camera, img[keep], fit.catalog_rows[keep])


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
    rot, camera = cand.rot_cam_from_icrs, cand.camera
    radius_rad = FIELD_MARGIN * math.radians(camera.fov_diagonal_deg) / 2.0
    near = visible_near(stars, rot.as_matrix()[2], radius_rad, camera.fx)
    field = _Field(x, y, stars, near, fit_focal)
    fit = _settle(field, rot, camera, cand.image_index, cand.catalog_rows)
    for _ in range(MAX_LEFT_OUT):
        better = _without_worst(field, fit) if fit.image_index.size >= MIN_STARS_TO_CHECK else None
        if better is None:
            break
        fit = better
    if fit_k1 and fit.image_index.size >= MIN_STARS_FOR_K1:  # lens distortion last, on the settled matches
        img = fit.image_index
        rot, camera, res = refine_pointing(fit.rot_cam_from_icrs, fit.camera, fit.ref_icrs, x[img], y[img],
                                           fit_focal=True, fit_k1=True)
        fit = FinalFit(rot, camera, img, fit.catalog_rows, fit.ref_icrs, res)
    return fit
