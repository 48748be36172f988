"""Area and polar moment of star triangles, planar and spherical (Cole & Crassidis 2004, 2006;
Huffman 2006 §5.4.2), and their 1-sigma errors from centroid noise.

Triangles are three unit vectors, arrays (..., 3, 3) (vertex, component).

- Planar (§1.21): the triangle of the chords between the unit vectors. Area by Heron's formula
  (in Kahan's cancellation-free arrangement), polar moment about the centroid
  ``I = A (a^2 + b^2 + c^2) / 36`` with the chord lengths a, b, c.
- Spherical (§1.20): area (spherical excess, steradians) by L'Huilier's theorem; polar moment
  ``I = sum_i theta_i^2 dA_i`` over the 4**levels triangles of a recursive subdivision (edge
  midpoints), with theta_i the arc from a sub-triangle's centroid to the whole triangle's
  (centroids as normalised vertex means). The sum misses each sub-triangle's own moment, so it
  falls short of the integral by about 4**-levels relatively; image and catalog triangles are
  computed alike, so this bias does not affect matching.

The errors (:func:`feature_sigmas`) are linearised: the Jacobian of (area, moment) with respect
to the two tangent-plane displacements of each vertex, by central differences, times an isotropic
angle error per axis.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..catalog import angle_from_chord
from ..errors import InvalidInputError
from ..frames import cross, normalize

VARIANTS = ("planar", "spherical")
SUBDIVISION_LEVELS = 2
"""Default subdivision depth of the spherical polar moment (16 sub-triangles; each level costs 4x)."""


def check_variant(variant: str) -> str:
    """The variant if it is one of :data:`VARIANTS`, else InvalidInputError."""
    if variant not in VARIANTS:
        raise InvalidInputError(f"variant must be one of {VARIANTS}, got {variant!r}")
    return variant


def planar_features(tri: NDArray) -> tuple[NDArray, NDArray]:
    """Area and polar moment (about the centroid) of the chord triangles (..., 3, 3)."""
    tri = np.asarray(tri, dtype=float)
    sides = np.linalg.norm(tri[..., [0, 1, 2], :] - tri[..., [1, 2, 0], :], axis=-1)
    c, b, a = np.moveaxis(np.sort(sides, axis=-1), -1, 0)  # a >= b >= c
    product = (a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c))
    area = 0.25 * np.sqrt(np.clip(product, 0.0, None))
    return area, area * np.sum(sides**2, axis=-1) / 36.0


def arc_from_chord(chord: NDArray) -> NDArray:
    """Arcs (radians) between unit vectors from their differences (..., 3): ``2 asin(|d| / 2)``,
    stable at small angles and cheaper than :func:`startrack.frames.angle_between`."""
    return angle_from_chord(np.sqrt(np.sum(chord * chord, axis=-1)))


def lhuilier_area(tri: NDArray) -> NDArray:
    """Spherical excess (steradians) of the spherical triangles (..., 3, 3), by L'Huilier's theorem."""
    sides = arc_from_chord(tri[..., [0, 1, 2], :] - tri[..., [1, 2, 0], :])
    s = 0.5 * np.sum(sides, axis=-1)
    product = np.tan(s / 2) * np.prod(np.tan((s[..., None] - sides) / 2), axis=-1)
    return 4.0 * np.arctan(np.sqrt(np.clip(product, 0.0, None)))


def subdivide(tri: NDArray, levels: int) -> NDArray:
    """The 4**levels sub-triangles (..., 4**levels, 3, 3) of spherical triangles (..., 3, 3), by
    splitting every edge at its (normalised) midpoint, ``levels`` times."""
    sub = np.asarray(tri, dtype=float)[..., None, :, :]
    for _ in range(levels):
        a, b, c = sub[..., 0, :], sub[..., 1, :], sub[..., 2, :]
        ab, bc, ca = normalize(a + b), normalize(b + c), normalize(c + a)
        out = np.empty((*sub.shape[:-2], 4, 3, 3))
        for part, corners in enumerate(((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))):
            for vertex, value in enumerate(corners):
                out[..., part, vertex, :] = value
        sub = out.reshape(*out.shape[:-4], -1, 3, 3)
    return sub


def spherical_features(tri: NDArray, levels: int = SUBDIVISION_LEVELS) -> tuple[NDArray, NDArray]:
    """Area (sr) and polar moment (sr rad^2) of spherical triangles (..., 3, 3) (see module docstring)."""
    tri = np.asarray(tri, dtype=float)
    sub = subdivide(tri, levels)
    centroid = normalize(np.sum(tri, axis=-2))
    theta = arc_from_chord(normalize(np.sum(sub, axis=-2)) - centroid[..., None, :])
    return lhuilier_area(tri), np.sum(theta**2 * lhuilier_area(sub), axis=-1)


def triangle_features(tri: NDArray, variant: str) -> tuple[NDArray, NDArray]:
    """(area, moment) of triangles (..., 3, 3) by ``variant`` ("planar" or "spherical")."""
    return planar_features(tri) if check_variant(variant) == "planar" else spherical_features(tri)


def feature_sigmas(tri: NDArray, sigma_rad: float, variant: str) -> tuple[float, float]:
    """1-sigma errors of (area, moment) of one triangle (3, 3) whose vertices each have an
    isotropic direction error of ``sigma_rad`` per axis (linearised propagation)."""
    tri = np.asarray(tri, dtype=float)
    step = max(sigma_rad, 1e-7)
    helper = np.where(np.abs(tri[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = normalize(cross(tri, helper))
    tangents = np.stack([e1, cross(tri, e1)], axis=1)  # (vertex, direction, 3)
    shifted = np.repeat(tri[None], 12, axis=0).reshape(3, 2, 2, 3, 3)  # vertex, direction, sign
    for v in range(3):
        for d in range(2):
            for s, sign in enumerate((1.0, -1.0)):
                shifted[v, d, s, v] = normalize(tri[v] + sign * step * tangents[v, d])
    area, moment = triangle_features(shifted, variant)
    grad_a = (area[..., 0] - area[..., 1]) / (2 * step)
    grad_i = (moment[..., 0] - moment[..., 1]) / (2 * step)
    return float(sigma_rad * np.sqrt(np.sum(grad_a**2))), float(sigma_rad * np.sqrt(np.sum(grad_i**2)))
