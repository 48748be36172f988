"""Which field of a split-FOV detector each spot came from, by the shape of its PSF (Samaan 2002 Eq. 4–5,
eqs. 4-5).

StarNav II superimposes two fields on one detector and tags them by deliberate astigmatism: one
field's stars are stretched along one direction, the other's along another. The seed classifies a
spot by its principal second moments about the centroid (x_c, y_c) over the pixels used for the
centroid, ``J1 = sum (y_i - y_c)^2`` and ``J2 = sum (x_i - x_c)^2`` (eq. 4), by J1 < J2 or J1 > J2
when ``(J1 - J2)^2`` exceeds a threshold (eq. 5). Eq. 4 has no intensity weights (the erratum):
unweighted, the sums measure the shape of the threshold mask, which for a faint star is a few
pixels. Here the moments are intensity weighted, ``J_xx = sum w_i (x_i - x_c)^2 / sum w_i`` (and
``J_yy``, ``J_xy``) with w_i the background-subtracted value of each mask pixel (``weighting =
"intensity"``; ``"mask"`` reproduces eq. 4 for comparison), so any elongation direction works:

- the spot's ellipticity ``e = (J_xx - J_yy, 2 J_xy) / (J_xx + J_yy)`` is compared with each
  field's expected one, ``e_h = (a^2 - b^2) / (a^2 + b^2) (cos 2 theta, sin 2 theta)`` for its PSF
  sigmas a >= b and direction theta (:class:`startrack.rig.PsfShape`; the pixel's own 1/12 px^2
  added to both axes);
- the spot goes to the nearest field; it is *ambiguous* when its position between the two
  nearest fields' e_h, ``t`` in [-1/2, 1/2] from the midpoint, lies within ``margin`` of the
  midpoint (for two orthogonal fields this is the seed's test on ``J2 - J1``, normalised by
  ``J1 + J2``). Ambiguous spots are tried in both fields by the solver.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..rig import RigHead

DEFAULT_MARGIN = 0.15
"""Half-width of the ambiguous band around the midpoint between two fields' ellipticities."""

MASK_SIGMAS = 2.0
"""Pixels above this many noise sigmas (background subtracted) within the window form the mask."""

WINDOW_SIGMAS = 3.0
"""The moments window reaches this many of the largest PSF sigma around the centroid."""

WEIGHTINGS = ("intensity", "mask")


@dataclass(frozen=True)
class SpotMoments:
    """Second moments (px^2) of N spots about their centroids: ``j_xx``, ``j_yy``, ``j_xy`` (N,)."""

    j_xx: NDArray[np.float64]
    j_yy: NDArray[np.float64]
    j_xy: NDArray[np.float64]

    @property
    def ellipticity(self) -> NDArray[np.float64]:
        """``(J_xx - J_yy, 2 J_xy) / (J_xx + J_yy)``, shape (N, 2) (NaN for an empty mask)."""
        total = self.j_xx + self.j_yy
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.column_stack([(self.j_xx - self.j_yy) / total, 2.0 * self.j_xy / total])

    @property
    def angle_deg(self) -> NDArray[np.float64]:
        """Direction of the long axis from +x towards +y, in [0, 180)."""
        return np.degrees(0.5 * np.arctan2(2.0 * self.j_xy, self.j_xx - self.j_yy)) % 180.0


def spot_moments(image, x, y, *, background: float, noise: float, radius_px: float,
                 weighting: str = "intensity") -> SpotMoments:
    """Second moments of the spots at (x, y) (px, our convention) in ``image`` (module docstring).

    Parameters
    ----------
    image : ndarray, shape (H, W)
    x, y : array_like, shape (N,)
        Centroids.
    background, noise : float
        The image's background level and noise (e.g. :class:`startrack.Detections` fields).
    radius_px : float
        Window radius around each centroid.
    weighting : {"intensity", "mask"}
        Intensity-weighted moments, or the unweighted sums of eq. 4 over the mask.
    """
    if weighting not in WEIGHTINGS:
        raise InvalidInputError(f"weighting must be one of {', '.join(WEIGHTINGS)}, got {weighting!r}")
    data = np.asarray(image, dtype=float)
    x, y = np.asarray(x, dtype=float).ravel(), np.asarray(y, dtype=float).ravel()
    r = int(math.ceil(radius_px))
    k = np.arange(-r, r + 1)
    cols = np.floor(x + 0.5).astype(int)[:, None, None] + k[None, None, :]  # (N, 1, S)
    rows = np.floor(y + 0.5).astype(int)[:, None, None] + k[None, :, None]  # (N, S, 1)
    rows, cols = np.broadcast_arrays(rows, cols)
    inside = (cols >= 0) & (cols < data.shape[1]) & (rows >= 0) & (rows < data.shape[0])
    dx, dy = cols - x[:, None, None], rows - y[:, None, None]
    values = np.where(inside, data[rows.clip(0, data.shape[0] - 1), cols.clip(0, data.shape[1] - 1)], 0.0) - background
    mask = inside & (dx * dx + dy * dy <= radius_px * radius_px) & (values > MASK_SIGMAS * max(noise, 1e-12))
    weight = np.where(mask, values if weighting == "intensity" else 1.0, 0.0)
    total = weight.sum(axis=(1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        moments = [np.sum(weight * a * b, axis=(1, 2)) / total for a, b in ((dx, dx), (dy, dy), (dx, dy))]
    return SpotMoments(*moments)


def expected_ellipticity(head: RigHead) -> NDArray[np.float64]:
    """A field's PSF ellipticity (2,) (module docstring), pixel size included."""
    psf = head.field_psf
    a2, b2 = psf.sigma_major_px**2 + 1.0 / 12.0, psf.sigma_minor_px**2 + 1.0 / 12.0
    two_theta = 2.0 * math.radians(psf.angle_deg)
    return (a2 - b2) / (a2 + b2) * np.array([math.cos(two_theta), math.sin(two_theta)])


@dataclass(frozen=True)
class FieldClassification:
    """The field of each of N spots.

    Attributes
    ----------
    names : tuple of str
        The fields (head names), in the rig's order.
    field : ndarray of int, shape (N,)
        Index into ``names`` of the nearest field (-1 when the spot's moments are undefined).
    ambiguous : ndarray of bool, shape (N,)
        Within the margin of two fields (or undefined): tried in both.
    ellipticity : ndarray, shape (N, 2)
    """

    names: tuple[str, ...]
    field: NDArray[np.int64]
    ambiguous: NDArray[np.bool_]
    ellipticity: NDArray[np.float64]

    def members(self, name: str) -> NDArray[np.int64]:
        """Indices of the spots tried in field ``name``: those classified there, and the ambiguous."""
        k = self.names.index(name)
        return np.flatnonzero((self.field == k) | self.ambiguous)


def classify_fields(moments: SpotMoments, fields: tuple[RigHead, ...] | list[RigHead],
                    margin: float = DEFAULT_MARGIN) -> FieldClassification:
    """Assign each spot to the field whose PSF ellipticity is nearest (module docstring)."""
    fields = tuple(fields)
    if len(fields) < 2 or any(h.psf is None for h in fields):
        raise InvalidInputError("classify_fields needs two or more fields, each with a PsfShape")
    if not 0.0 <= margin < 0.5:
        raise InvalidInputError(f"margin must be in [0, 0.5), got {margin!r}")
    expected = np.array([expected_ellipticity(h) for h in fields])  # (F, 2)
    e = moments.ellipticity
    dist = np.linalg.norm(e[:, None, :] - expected[None, :, :], axis=2)  # (N, F)
    defined = np.all(np.isfinite(e), axis=1)
    order = np.argsort(np.where(defined[:, None], dist, 0.0), axis=1)
    best, second = order[:, 0], order[:, 1]
    e1, e2 = expected[best], expected[second]
    span = np.sum((e1 - e2) ** 2, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.sum((e - 0.5 * (e1 + e2)) * (e1 - e2), axis=1) / span
    ambiguous = ~defined | ~(span > 0) | (np.abs(t) < margin)
    return FieldClassification(tuple(h.name for h in fields), np.where(defined, best, -1).astype(np.int64),
                               ambiguous, e)


def moments_radius_px(fields: tuple[RigHead, ...] | list[RigHead]) -> float:
    """The moments window for these fields: :data:`WINDOW_SIGMAS` of the largest PSF sigma (>= 2 px)."""
    return max(2.0, WINDOW_SIGMAS * max(h.field_psf.sigma_major_px for h in fields))
