"""Stars of a head predicted through its mounting from a body attitude, and matched in windows
(Samaan 2002 Eq. 1–3 steps 2-4, per field of view: "prediction projects each FOV's corners separately").

A body attitude ``rot_body_from_icrs`` and a head's mounting give the head's attitude
``rot_cam_from_body * rot_body_from_icrs``; the brightest catalog stars it puts inside the head's
image are matched one to one with the head's stars within a radius
(:class:`startrack.track._windows.WindowMatcher`, the tracking-mode matcher). The radius follows the
attitude's uncertainty carried into the head (:func:`predicted_sigma_px`): a lost-in-space solve
of one head knows its roll poorly, and that roll is a cross-boresight shift for a head mounted at
90 degrees.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..identify import FieldStars
from ..rig import RigHead
from ..track import EXTRA_PREDICTED, WindowMatcher, one_to_one
from ._joint import HeadMatch
from ._stars import HeadStars

MIN_PREDICTED = 30
"""At least this many of the brightest catalog stars in the field are predicted."""


def predicted_sigma_px(covariance_body: NDArray, head: RigHead) -> float:
    """1-sigma (px) of where an attitude with this body-frame covariance (rad^2) puts the head's
    stars: the largest cross-boresight axis of the covariance at the focal length, and the roll
    about the boresight at the image's half-diagonal, added in quadrature."""
    b = head.boresight_body
    across = np.eye(3) - np.outer(b, b)
    cross_var = float(np.linalg.eigvalsh(across @ covariance_body @ across).max())
    roll_var = float(b @ covariance_body @ b)
    cam = head.camera
    half_diag_px = 0.5 * math.hypot(cam.width, cam.height)
    return math.sqrt(max(cross_var, 0.0) * max(cam.fx, cam.fy) ** 2 + max(roll_var, 0.0) * half_diag_px**2)


def head_matcher(head: RigHead, catalog: FieldStars) -> WindowMatcher:
    """The window matcher of one head (it keeps the catalog cone around the head's boresight)."""
    return WindowMatcher(head.camera, catalog)


def predicted_in_head(matcher: WindowMatcher, head: RigHead, rot_body_from_icrs: Rotation, margin_px: float,
                      count: int) -> tuple[NDArray[np.int64], NDArray, NDArray]:
    """Indices (into the matcher's star set), x and y (px) of the ``count`` brightest catalog stars
    that the body attitude puts inside the head's image."""
    matrix = (head.rot_cam_from_body * rot_body_from_icrs).as_matrix()
    return matcher.predicted(matrix, margin_px / head.camera.fx, count)


def match_predicted(stars: HeadStars, matcher: WindowMatcher, rot_body_from_icrs: Rotation,
                    radius_px: float) -> tuple[HeadMatch, int]:
    """The head's stars matched one to one (closest first) with the catalog stars predicted within
    ``radius_px``; and how many catalog stars were predicted in the image."""
    if len(stars) == 0:
        return HeadMatch.empty(stars), 0
    count = max(MIN_PREDICTED, int(EXTRA_PREDICTED * len(stars)))
    idx, px, py = predicted_in_head(matcher, stars.head, rot_body_from_icrs, radius_px, count)
    img, cat = one_to_one(stars.x, stars.y, px, py, radius_px)
    catalog = matcher.stars
    return HeadMatch(stars, img, catalog.rows[idx[cat]], catalog.vectors[idx[cat]]), int(idx.size)
