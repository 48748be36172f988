"""What triangle_match and rate_match take: directions (N, 3), a tolerance of a few centroid
sigmas, a finite rate and a non-zero interval. Before, a NaN direction was taken, pixel
positions (N, 2) gave a raw IndexError, a 0.5 rad tolerance gave OK 125 deg from the truth, and
dt_s = 0 or a NaN rate gave NO_MATCH."""

from __future__ import annotations

import numpy as np
import pytest
from test_track_relative import _frames

from startrack.errors import InvalidInputError
from startrack.track import rate_match, triangle_match

TOL_RAD = 1e-4  # rad: about 4 sigma of a pair's difference (10 arcsec)


def _broken(vectors: np.ndarray, how: str) -> np.ndarray:
    if how == "nan row":
        return np.vstack([vectors[:1] * np.nan, vectors[1:]])
    if how == "zero row":
        return np.vstack([np.zeros((1, 3)), vectors[1:]])
    return vectors[:, :2]  # pixel-like (N, 2)


@pytest.mark.parametrize("how", ["nan row", "zero row", "two columns"])
def test_directions_that_are_not_unit_vectors_are_refused(how):
    first, second, _, rate, dt = _frames(1)
    said = r"vectors of shape \(N, 3\), got shape \(\d+, 2\)" if how == "two columns" else "finite, non-zero vectors"
    with pytest.raises(InvalidInputError, match=r"first must be " + said):
        triangle_match(_broken(first, how), second, TOL_RAD)
    with pytest.raises(InvalidInputError, match=r"second must be " + said):
        rate_match(first, _broken(second, how), rate, dt, TOL_RAD)


@pytest.mark.parametrize("tol_rad", [0.0, -1e-4, 0.5, float("nan"), "1e-4"])
def test_a_tolerance_outside_a_few_centroid_sigmas_is_refused(tol_rad):
    first, second, _, rate, dt = _frames(1)
    for match in (lambda: triangle_match(first, second, tol_rad), lambda: rate_match(first, second, rate, dt, tol_rad)):
        with pytest.raises(InvalidInputError, match="tol_rad must be an angle in"):
            match()


@pytest.mark.parametrize(("rate", "dt", "words"), [
    ((np.nan, 0.0, 0.0), 0.5, "rate_rad_s must be 3 finite numbers"),
    ((0.01, 0.0), 0.5, "rate_rad_s must be 3 finite numbers"),
    ((0.01, 0.0, 0.0), 0.0, "dt_s must be a finite, non-zero"),
    ((0.01, 0.0, 0.0), float("inf"), "dt_s must be a finite, non-zero"),
])
def test_rate_match_refuses_a_rate_or_interval_it_cannot_turn_stars_by(rate, dt, words):
    first, second, _, _, _ = _frames(1)
    with pytest.raises(InvalidInputError, match=words):
        rate_match(first, second, rate, dt, TOL_RAD)


def test_triangle_match_needs_triangles_of_at_least_three_stars():
    first, second, _, _, _ = _frames(1)
    with pytest.raises(InvalidInputError, match="max_stars must be an integer >= 3"):
        triangle_match(first, second, TOL_RAD, max_stars=2)
