"""Cone search against brute force (stable angles), on the real catalog."""

import numpy as np
import pytest

from startrack.catalog import ConeIndex, StarCatalog, cone_search, load_catalog
from startrack.catalog._thinning import fibonacci_sphere
from startrack.errors import InvalidInputError
from startrack.frames import angle_between
from startrack.units import DEG


@pytest.fixture(scope="module")
def catalog() -> StarCatalog:
    return load_catalog()


@pytest.fixture(scope="module")
def bright(catalog) -> StarCatalog:
    return catalog.brighter_than(7.5)


def brute_force(vectors: np.ndarray, center: np.ndarray, radius: float) -> np.ndarray:
    return np.flatnonzero(angle_between(vectors, center) <= radius)


def centers(n: int, seed: int) -> np.ndarray:
    v = np.random.default_rng(seed).normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


@pytest.mark.parametrize("radius_deg", [0.5, 5.0, 30.0])
def test_query_matches_brute_force(bright, radius_deg):
    vectors = bright.vectors()
    index = ConeIndex(vectors)
    for center in centers(20, seed=int(radius_deg * 10)):
        expected = brute_force(vectors, center, radius_deg * DEG)
        np.testing.assert_array_equal(index.query(center, radius_deg * DEG), expected)
        np.testing.assert_array_equal(cone_search(bright, center, radius_deg * DEG), expected)


def test_query_many_matches_query(bright):
    index = ConeIndex(bright.vectors())
    many = index.query_many(fibonacci_sphere(50), 8 * DEG)
    assert len(many) == 50
    for center, found in zip(fibonacci_sphere(50), many, strict=True):
        np.testing.assert_array_equal(found, index.query(center, 8 * DEG))


def test_cone_search_at_another_epoch(catalog):
    barnard = np.flatnonzero(catalog.hip == 87937)[0]
    center = catalog.vectors(2050.0)[barnard]
    found_2050 = cone_search(catalog, center, 1.0 / 3600 * DEG, epoch_jyear=2050.0)
    found_1991 = cone_search(catalog, center, 1.0 / 3600 * DEG)
    assert barnard in found_2050 and barnard not in found_1991


def test_whole_sky_and_empty_radius(bright):
    index = ConeIndex(bright.vectors())
    assert len(index.query([0, 0, 1], np.pi)) == len(bright)
    assert len(index.query([0, 0, 2.0], 0.0)) == 0  # centre is normalised


def test_invalid_inputs(bright):
    index = ConeIndex(bright.vectors())
    with pytest.raises(InvalidInputError, match="radius_rad"):
        index.query([0, 0, 1], -0.1)
    with pytest.raises(InvalidInputError, match="center"):
        index.query([0, 0, 0], 0.1)
    with pytest.raises(InvalidInputError, match="centers"):
        index.query_many([0, 0, 1], 0.1)
    with pytest.raises(InvalidInputError, match="vectors"):
        ConeIndex(np.ones((3, 2)))
