"""Identification by proximity: catalog stars predicted by an attitude, matched to detections in
windows around them, then the attitude from the matched stars (Samaan 2002 Eq. 1–3 steps 2-5; Jacobs 1995
§4.1.4: the search area follows the prediction uncertainty).

The brightest catalog stars predicted inside the image (a few more than there are detections)
are matched to the detections within ``window_px`` (the prediction's uncertainty); the attitude
is fitted to those pairs (q-method); the same stars are matched again within ``match_px`` of the
fitted attitude and the attitude refitted. The geometry of the matched stars confirms the result:
the caller accepts it only if enough stars match with residuals at the centroid-noise level.

:class:`WindowMatcher` does this frame after frame: it keeps the catalog stars of a cone a little
wider than the field (queried again only when the boresight has moved by more than the extra
width), so that a frame costs a projection of the brightest of those stars, two small one-to-one
matches and two q-method fits on plain arrays (:mod:`._quaternions`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..catalog import query_cone
from ..identify import FieldStars, closest_pairs_first, match_nearest
from ._quaternions import fit_quat, quat_matrix

EXTRA_PREDICTED = 2.0
"""Predicted stars kept: this many times the number of detections (at least 30)."""

CONE_SLACK_RAD = math.radians(2.0)
"""Extra radius of the cached catalog cone: it is queried again when the boresight has moved this far."""

PREFIX_FACTOR = 2.0
"""The brightest ``PREFIX_FACTOR * count / (image share of the cone)`` stars of the cone are
projected first; all of them only if fewer than ``count`` of those fall inside the image."""

MAX_CONE_RAD = 1.5
"""Largest search cone around the boresight (rad)."""

DENSE_PAIRS_LIMIT = 200_000
"""Above this many (detection, predicted star) pairs, the pairs come from :func:`match_nearest`'s KD-trees."""


@dataclass(frozen=True)
class WindowMatch:
    """Result of matching in windows: the fitted attitude (None if too few stars matched), the
    image indices and catalog rows matched, and the rms pixel residual."""

    rot_cam_from_icrs: Rotation | None
    image_index: NDArray[np.int64]
    catalog_rows: NDArray[np.int64]
    residual_rms_px: float


def one_to_one(x: NDArray, y: NDArray, px: NDArray, py: NDArray,
               radius_px: float) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Pairs (detection index, predicted index) within the radius, each star used once, closest first.

    The pairs of :func:`startrack.identify._verify.match_nearest` (greedy, closest pair first);
    for the few dozen stars of a tracked frame the candidate pairs come from one dense distance
    table rather than KD-trees.
    """
    if x.size * px.size > DENSE_PAIRS_LIMIT or x.size == 0 or px.size == 0:
        return match_nearest(x, y, px, py, radius_px)
    d2 = ((x[:, None] - px) ** 2 + (y[:, None] - py) ** 2).ravel()
    flat = np.flatnonzero(d2 <= radius_px * radius_px)  # row-major, as np.nonzero
    rows, cols = np.divmod(flat, px.size)
    return closest_pairs_first(rows, cols, d2[flat])


def project(camera: Camera, vectors: NDArray) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Pixel positions (x, y), each (K,), of camera-frame vectors given as columns (3, K).

    :meth:`Camera.vector_to_pixel`; when every vector is in front of a distortion-free camera
    (the tracked case), the pinhole projection is written out here, without that method's
    handling of vectors behind the camera (three times faster on a few hundred stars).
    """
    if camera.has_distortion or not np.all(vectors[2] > 0.0):
        return camera.vector_to_pixel(vectors.T)
    inv_z = 1.0 / vectors[2]
    fx = camera.x_sign * camera.fx  # a mirrored camera's x runs against its x axis
    return camera.cx + fx * (vectors[0] * inv_z), camera.cy + camera.fy * (vectors[1] * inv_z)


def _angle_rad(u: tuple[float, float, float], v: tuple[float, float, float]) -> float:
    """Angle (rad, 0 to pi) between two 3-vectors given as tuples, by the stable atan2 form of
    :func:`startrack.frames.angle_between` on plain floats (no ``acos`` of a dot product, which a
    rounded dot of -1.0000000000000002 between opposite unit vectors takes out of its domain)."""
    cx, cy, cz = u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]
    return math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), u[0] * v[0] + u[1] * v[1] + u[2] * v[2])


class WindowMatcher:
    """:func:`match_in_windows` for a sequence of frames of one camera and star set.

    Parameters
    ----------
    camera : Camera
    stars : FieldStars
        Catalog stars, brightest first (:func:`startrack.identify._field_stars.field_stars`).
    slack_rad : float
        Extra radius of the cached catalog cone (rad).
    """

    def __init__(self, camera: Camera, stars: FieldStars, slack_rad: float = CONE_SLACK_RAD):
        self.camera, self.stars, self.slack_rad = camera, stars, slack_rad
        self._half_diag = math.radians(camera.fov_diagonal_deg) / 2.0
        self._centre: tuple[float, float, float] | None = None
        self._radius = -1.0
        self._image_fraction = 1.0  # the share of the cached cone's stars expected in the image (roughly)
        self._idx = np.zeros(0, dtype=np.int64)
        self._vectors = np.zeros((3, 0))

    def _cone(self, boresight: NDArray, cone_rad: float) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """Indices (ascending, so brightest first) and ICRS vectors (3, K) of a set of catalog stars
        that holds every star within ``cone_rad`` of the boresight."""
        b = tuple(boresight.tolist())
        if self._centre is not None and _angle_rad(b, self._centre) + cone_rad <= self._radius:
            return self._idx, self._vectors
        radius = min(cone_rad + self.slack_rad, math.pi)
        self._idx = np.asarray(query_cone(self.stars.tree, b, radius, return_sorted=True), dtype=np.int64)
        self._vectors = np.ascontiguousarray(self.stars.vectors[self._idx].T)
        self._centre, self._radius = b, radius
        image_sr = (self.camera.width / self.camera.fx) * (self.camera.height / self.camera.fy)
        self._image_fraction = min(1.0, image_sr / (2.0 * math.pi * (1.0 - math.cos(radius))))
        return self._idx, self._vectors

    def predicted(self, matrix: NDArray, margin_rad: float, count: int) -> tuple[NDArray, NDArray, NDArray]:
        """The ``count`` brightest catalog stars predicted inside the image by an attitude.

        Parameters
        ----------
        matrix : ndarray, shape (3, 3)
            ``rot_cam_from_icrs`` as a matrix.
        margin_rad : float
            Widens the cone around the boresight searched (the prediction's uncertainty).
        count : int

        Returns
        -------
        idx : ndarray of int, shape (K,)
            Indices into the star set, brightest first (K <= count).
        x, y : ndarray, shape (K,)
            Their predicted pixel positions.
        """
        cone = min(self._half_diag + margin_rad, MAX_CONE_RAD)
        idx, vectors = self._cone(matrix[2], cone)
        first = min(len(idx), math.ceil(PREFIX_FACTOR * count / self._image_fraction))
        found = self._inside(idx[:first], vectors[:, :first], matrix, cone)
        if found[0].size < count and first < len(idx):  # too few in the brightest prefix: all of them
            found = self._inside(idx, vectors, matrix, cone)
        idx, x, y = found
        return idx[:count], x[:count], y[:count]

    def _inside(self, idx: NDArray, vectors: NDArray, matrix: NDArray, cone_rad: float
                ) -> tuple[NDArray, NDArray, NDArray]:
        """Those of the stars within ``cone_rad`` of the boresight that fall inside the image, and
        their pixel positions."""
        cam = matrix @ vectors
        near = np.flatnonzero(cam[2] >= math.cos(cone_rad))
        px, py = project(self.camera, cam[:, near])
        inside = np.flatnonzero(self.camera.in_image(px, py))
        return idx[near[inside]], px[inside], py[inside]

    def match(self, x: NDArray, y: NDArray, matrix: NDArray, *, window_px: float, match_px: float,
              min_stars: int) -> WindowMatch:
        """Match detections to the stars an attitude (a 3 x 3 ``rot_cam_from_icrs``) predicts and
        refit it; see :func:`match_in_windows` for the parameters and result."""
        camera = self.camera
        count = max(30, int(EXTRA_PREDICTED * len(x)))
        idx, px, py = self.predicted(matrix, window_px / camera.fx, count)
        reference = self.stars.vectors[idx]
        reference_t = reference.T
        observed = camera.pixel_to_vector(x, y)
        for radius in (window_px, match_px):
            img, cat = one_to_one(x, y, px, py, radius)
            if img.size < min_stars:
                return WindowMatch(None, img, self.stars.rows[idx[cat]], float("nan"))
            quat = fit_quat(observed[img], reference[cat])
            px, py = project(camera, quat_matrix(quat) @ reference_t)
        rms = float(np.sqrt(np.mean((px[cat] - x[img]) ** 2 + (py[cat] - y[img]) ** 2)))
        return WindowMatch(Rotation.from_quat(quat), img, self.stars.rows[idx[cat]], rms)


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
        Catalog stars, brightest first (:func:`startrack.identify._field_stars.field_stars`).
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
    return WindowMatcher(camera, stars).match(np.asarray(x, dtype=float), np.asarray(y, dtype=float),
                                              rot_predicted.as_matrix(), window_px=window_px, match_px=match_px,
                                              min_stars=min_stars)
