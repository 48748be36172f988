"""LGL nodes, weights and differentiation matrix against known values and exact polynomials."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.polynomial import legendre
from numpy.polynomial import polynomial as P

from startrack.adcs._lgl import lgl_grid, time_nodes
from startrack.errors import InvalidInputError


def test_three_nodes_match_the_textbook_values():
    grid = lgl_grid(3)
    np.testing.assert_allclose(grid.tau, [-1.0, 0.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(grid.weights, [1 / 3, 4 / 3, 1 / 3], rtol=1e-14)
    np.testing.assert_allclose(grid.diff, [[-1.5, 2.0, -0.5], [-0.5, 0.0, 0.5], [0.5, -2.0, 1.5]], atol=1e-14)


@pytest.mark.parametrize("n", [4, 7, 10, 16])
def test_interior_nodes_are_the_roots_of_the_legendre_derivative(n):
    grid = lgl_grid(n)
    series = np.zeros(n)
    series[-1] = 1.0
    np.testing.assert_allclose(legendre.legval(grid.tau[1:-1], legendre.legder(series)), 0.0, atol=1e-10)
    assert grid.tau[0] == -1.0 and grid.tau[-1] == 1.0 and np.all(np.diff(grid.tau) > 0)


@pytest.mark.parametrize("n", [4, 10, 13])
def test_differentiation_is_exact_up_to_degree_n_minus_1(n):
    grid = lgl_grid(n)
    coef = np.random.default_rng(n).normal(size=n)  # degree n - 1
    np.testing.assert_allclose(grid.diff @ P.polyval(grid.tau, coef), P.polyval(grid.tau, P.polyder(coef)),
                               atol=1e-10 * np.abs(coef).sum() * n * n)
    # tau^n is beyond the interpolant: D is no longer exact
    assert np.max(np.abs(grid.diff @ grid.tau**n - n * grid.tau ** (n - 1))) > 1e-3


@pytest.mark.parametrize("n", [4, 10, 13])
def test_quadrature_is_exact_up_to_degree_2n_minus_3(n):
    grid = lgl_grid(n)
    for degree in range(2 * n - 2):
        exact = 0.0 if degree % 2 else 2.0 / (degree + 1)
        assert grid.weights @ grid.tau**degree == pytest.approx(exact, abs=1e-13)
    degree = 2 * n - 2  # the first degree it misses
    assert abs(grid.weights @ grid.tau**degree - 2.0 / (degree + 1)) > 1e-10  # vs < 1e-13 above


def test_time_nodes_and_refusals():
    grid = lgl_grid(5)
    t = time_nodes(grid, 3.0, 10.0)
    assert t[0] == 3.0 and t[-1] == 13.0
    for bad in (1, 0, 2.5, "4"):
        with pytest.raises(InvalidInputError, match="n_nodes"):
            lgl_grid(bad)
