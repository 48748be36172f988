"""Identification by proximity: catalog stars predicted by an attitude, matched to detections in
windows around them, then the attitude from the matched stars (seed 004 §2.2 steps 2-5; seed 002
§4.1.4: the search area follows the prediction uncertainty).

The brightest catalog stars predicted inside the image (a few more than there are detections)
are matched to the detections within ``window_px`` (the prediction's uncertainty); the attitude
is fitted to those pairs (q-method); the same stars are matched again within ``match_px`` of the
fitted attitude and the attitude refitted. The geometry of the matched stars confirms the result:
the caller accepts it only if enough stars match with residuals at the centroid-noise level.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..attitude.qmethod import q_method_quaternions
from ..camera import Camera
from ..identify.field_stars import FieldStars
from ..identify.verify import match_nearest

EXTRA_PREDICTED = 2.0
"""Predicted stars kept: this many times the number of detections (at least 30)."""


@dataclass(frozen=True)
class WindowMatch:
    """Result of matching in windows: the fitted attitude (None if too few stars matched), the
    image indices and catalog rows matched, and the rms pixel residual."""

    rot_cam_from_icrs: Rotation | None
    image_index: NDArray[np.int64]
    catalog_rows: NDArray[np.int64]
    residual_rms_px: float


def _predicted_stars(stars: FieldStars, matrix: NDArray, camera: Camera, margin_rad: float, count: int) -> NDArray:
    """Indices (into ``stars``) of the ``count`` brightest stars predicted inside the image."""
    half_diag = math.radians(camera.fov_diagonal_deg) / 2.0 + margin_rad
    chord = 2.0 * math.sin(min(half_diag, 1.5) / 2.0)
    idx = np.asarray(stars.tree.query_ball_point(matrix[2], chord, return_sorted=True), dtype=np.int64)
    x, y = camera.vector_to_pixel(stars.vectors[idx] @ matrix.T)
    return idx[camera.in_image(x, y)][:count]


def _fit(observed: NDArray, reference: NDArray) -> NDArray:
    weights = np.full((1, len(observed)), 1.0 / len(observed))
    return Rotation.from_quat(q_method_quaternions(observed[None], reference[None], weights)[0]).as_matrix()


def match_in_windows(x: NDArray, y: NDArray, camera: Camera, rot_predicted: Rotation, stars: FieldStars, *,
                     window_px: float, match_px: float, min_stars: int) -> WindowMatch:
    """Match detections to the catalog stars an attitude predicts, and refit the attitude.

    Parameters
    ----------
    x, y : ndarray, shape (N,)
        Detections (our pixel convention), brightest first.
    camera : Camera
    rot_predicted : Rotation
        Predicted ``rot_cam_from_icrs``.
    stars : FieldStars
        Catalog stars, brightest first (:func:`startrack.identify.field_stars.field_stars`).
    window_px : float
        Half-size of the search window around each predicted star (the prediction uncertainty).
    match_px : float
        Match radius after the attitude is refitted.
    min_stars : int
        Fewest matched stars for a result.

    Returns
    -------
    WindowMatch
        ``rot_cam_from_icrs`` is None when fewer than ``min_stars`` stars matched.
    """
    matrix = rot_predicted.as_matrix()
    count = max(30, int(EXTRA_PREDICTED * len(x)))
    idx = _predicted_stars(stars, matrix, camera, window_px / camera.fx, count)
    observed_all = camera.pixel_to_vector(x, y)
    img = cat = np.zeros(0, dtype=np.int64)
    for radius in (window_px, match_px):
        px, py = camera.vector_to_pixel(stars.vectors[idx] @ matrix.T)
        img, cat = match_nearest(x, y, px, py, radius)
        if img.size < min_stars:
            return WindowMatch(None, img, stars.rows[idx[cat]], float("nan"))
        matrix = _fit(observed_all[img], stars.vectors[idx[cat]])
    px, py = camera.vector_to_pixel(stars.vectors[idx[cat]] @ matrix.T)
    rms = float(np.sqrt(np.mean((px - x[img]) ** 2 + (py - y[img]) ** 2)))
    return WindowMatch(Rotation.from_matrix(matrix), img, stars.rows[idx[cat]], rms)
