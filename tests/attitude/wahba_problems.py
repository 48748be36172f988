"""Seeded Wahba problems with known truth, shared by the attitude tests."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from startrack.frames import normalize


def random_unit_vectors(shape: tuple[int, ...], rng: np.random.Generator) -> np.ndarray:
    """Unit vectors of shape ``shape + (3,)``, uniform on the sphere."""
    return normalize(rng.normal(size=shape + (3,)))


def cone_vectors(
    shape: tuple[int, ...], half_angle_rad: float, rng: np.random.Generator
) -> np.ndarray:
    """Unit vectors uniform in a cone of the given half-angle about +z (a star tracker field)."""
    cos_z = rng.uniform(np.cos(half_angle_rad), 1.0, size=shape)
    phi = rng.uniform(0.0, 2.0 * np.pi, size=shape)
    sin_z = np.sqrt(1.0 - cos_z**2)
    return np.stack([sin_z * np.cos(phi), sin_z * np.sin(phi), cos_z], axis=-1)


def perturb(vectors: np.ndarray, sigma_rad, rng: np.random.Generator) -> np.ndarray:
    """Unit vectors turned by small-angle noise perpendicular to them.

    Each vector moves along its two tangent directions by independent N(0, sigma^2) angles
    (sigma per axis, radians, broadcast against ``vectors.shape[:-1]``): the QUEST measurement
    model.
    """
    helper = np.where(np.abs(vectors[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    e1 = normalize(np.cross(vectors, helper))
    e2 = np.cross(vectors, e1)
    sigma = np.broadcast_to(np.asarray(sigma_rad, dtype=float), vectors.shape[:-1])
    n1 = rng.normal(size=sigma.shape) * sigma
    n2 = rng.normal(size=sigma.shape) * sigma
    return turn(vectors, n1[..., None] * e1 + n2[..., None] * e2)


def turn(vectors: np.ndarray, tangent: np.ndarray) -> np.ndarray:
    """Move unit vectors along tangent vectors by the angle |tangent| (exact great circle)."""
    angle = np.linalg.norm(tangent, axis=-1, keepdims=True)
    direction = tangent / np.where(angle > 0.0, angle, 1.0)
    return vectors * np.cos(angle) + direction * np.sin(angle)


def problems(
    truth: Rotation, reference: np.ndarray, sigma_rad, rng: np.random.Generator
) -> np.ndarray:
    """Observed vectors ``truth.apply(reference)`` plus perpendicular noise (per-problem truth)."""
    matrices = truth.as_matrix()
    if matrices.ndim == 2:
        exact = reference @ matrices.T
    else:
        exact = np.einsum("mij,mnj->mni", matrices, reference)
    return perturb(exact, sigma_rad, rng)


def align(observed: np.ndarray, reference: np.ndarray, weights=None) -> Rotation:
    """scipy's answer, one problem at a time: the rotation mapping reference onto observed."""
    if observed.ndim == 2:
        return Rotation.align_vectors(observed, reference, weights)[0]
    w = [None] * len(observed) if weights is None else weights
    pairs = zip(observed, reference, w, strict=True)
    return Rotation.concatenate([Rotation.align_vectors(o, r, wi)[0] for o, r, wi in pairs])


def angle_rad(a: Rotation, b: Rotation) -> np.ndarray:
    """Angle between two (stacks of) attitudes, radians (DESIGN.md attitude error)."""
    return (a * b.inv()).magnitude()
