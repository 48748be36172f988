"""Per-star angle residuals after a fit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from wahba_problems import random_unit_vectors, turn

from startrack.attitude import angle_residuals, solve_wahba
from startrack.errors import InvalidInputError
from startrack.frames import normalize


def _tangents(vectors, angles, rng):
    """Tangent vectors of the given lengths, perpendicular to each unit vector."""
    side = normalize(np.cross(vectors, random_unit_vectors(vectors.shape[:-1], rng)))
    return side * np.asarray(angles)[..., None]


def test_known_offsets_are_recovered_down_to_tiny_angles():
    # The atan2 form keeps relative precision where arccos(dot) would return 0 or ~1e-8.
    rng = np.random.default_rng(40)
    attitude = Rotation.random(random_state=rng)
    reference = random_unit_vectors((5,), rng)
    offsets = np.array([1e-12, 1e-9, 1e-6, 1e-3, 1.0])
    exact = attitude.apply(reference)
    observed = turn(exact, _tangents(exact, offsets, rng))
    residuals = angle_residuals(attitude, observed, reference)
    np.testing.assert_allclose(residuals, offsets, rtol=1e-6, atol=1e-15)  # arccos: 0 at 1e-9


def test_residuals_of_a_noise_free_fit_vanish_and_batch():
    rng = np.random.default_rng(41)
    truth = Rotation.random(4, random_state=rng)
    reference = random_unit_vectors((4, 6), rng)
    observed = np.einsum("mij,mnj->mni", truth.as_matrix(), reference)
    fit = solve_wahba(observed, reference)
    residuals = angle_residuals(fit.rotation, observed, reference)
    assert residuals.shape == (4, 6)
    assert np.max(residuals) < 1e-14
    single = angle_residuals(truth[2], observed[2], reference[2])
    assert single.shape == (6,) and np.max(single) < 1e-14


def test_one_rotation_for_a_whole_batch():
    rng = np.random.default_rng(42)
    attitude = Rotation.random(random_state=rng)
    reference = random_unit_vectors((3, 4), rng)
    observed = attitude.apply(reference.reshape(-1, 3)).reshape(3, 4, 3)
    assert np.max(angle_residuals(attitude, observed, reference)) < 1e-14


def test_rotation_stack_must_match_the_batch():
    vectors = np.tile(np.eye(3), (2, 1, 1))
    with pytest.raises(InvalidInputError, match="rotation must be a single Rotation or a stack"):
        angle_residuals(Rotation.identity(3), vectors, vectors)
    with pytest.raises(InvalidInputError, match="rotation must be a single Rotation"):
        angle_residuals(Rotation.identity(2), np.eye(3), np.eye(3))
