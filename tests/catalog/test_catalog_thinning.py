"""Uniform thinning (Huffman 2006 §5.5.4): the union of each region's brightest stars."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from startrack.catalog import ConeIndex, StarCatalog, load_catalog, thin_uniform
from startrack.catalog._thinning import fibonacci_sphere, sky_sample_points
from startrack.errors import InvalidInputError
from startrack.frames import vector_to_radec
from startrack.units import DEG


def random_sky(n: int, seed: int) -> StarCatalog:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    ra, dec = vector_to_radec(v)
    return StarCatalog.from_positions(ra, dec, np.round(rng.uniform(0, 8, n), 1))


def top_k_union(cat: StarCatalog, k: int, radius: float) -> set[int]:
    """The reference rule, written out region by region."""
    order = np.argsort(cat.v_mag, kind="stable")
    rank = np.empty(len(cat), dtype=int)
    rank[order] = np.arange(len(cat))
    keep: set[int] = set()
    for members in ConeIndex(cat.vectors()).query_many(sky_sample_points(radius), radius):
        keep.update(members[np.argsort(rank[members])][:k].tolist())
    return keep


def test_matches_region_by_region_rule():
    cat = random_sky(20_000, seed=3)
    thinned = thin_uniform(cat, 5, 10 * DEG)
    assert set(thinned.hip.tolist()) == {int(cat.hip[i]) for i in top_k_union(cat, 5, 10 * DEG)}
    assert np.all(np.diff(thinned.v_mag) >= 0)  # brightest first
    again = thin_uniform(cat, 5, 10 * DEG)
    np.testing.assert_array_equal(again.hip, thinned.hip)  # deterministic


def test_each_region_keeps_its_brightest_and_density_is_bounded():
    cat = random_sky(20_000, seed=4)
    k, radius = 4, 8 * DEG
    thinned = thin_uniform(cat, k, radius)
    centers = sky_sample_points(radius)
    full = ConeIndex(cat.vectors()).query_many(centers, radius)
    kept = ConeIndex(thinned.vectors()).query_many(centers, radius)
    neighbours = ConeIndex(centers).query_many(centers, 2 * radius)
    for f, kp, nb in zip(full, kept, neighbours, strict=True):
        brightest = np.sort(cat.v_mag[f])[:k]
        np.testing.assert_array_equal(np.sort(thinned.v_mag[kp])[:len(brightest)], brightest)
        assert len(kp) <= k * len(nb)  # only regions overlapping this one add stars


def test_sample_points_cover_the_sphere():
    radius = 2.5 * DEG
    points = sky_sample_points(radius)
    assert len(points) == int(np.ceil(4 * np.pi / radius**2))
    probes = fibonacci_sphere(200_000)
    nearest = cKDTree(points).query(probes)[0]  # chord to the nearest sample point
    assert np.max(2 * np.arcsin(nearest / 2)) < 0.8 * radius  # measured: 0.75-0.77


def test_full_catalog_no_empty_region():
    catalog = load_catalog()
    radius = 2.5 * DEG
    thinned = thin_uniform(catalog, 8, radius)
    assert 15_000 < len(thinned) < 30_000
    centers = sky_sample_points(radius)
    full = ConeIndex(catalog.vectors()).query_many(centers, radius)
    kept = ConeIndex(thinned.vectors()).query_many(centers, radius)
    n_full = np.array([len(f) for f in full])
    n_kept = np.array([len(kp) for kp in kept])
    assert np.all(n_kept >= np.minimum(8, n_full))
    assert np.all(n_full > 0)


def test_huffman_reduced_catalog_size():
    # Huffman 2006: 5,060 stars brighter than V 6, 8 brightest per 30 deg FOV -> 540 stars.
    thinned = thin_uniform(load_catalog().brighter_than(6.0), 8, 15 * DEG)
    assert 400 < len(thinned) < 800
    assert thinned.hip[0] == 32349  # Sirius first


@pytest.mark.parametrize(("k", "radius"), [(0, 0.1), (2.5, 0.1), (3, 0.0), (3, 4.0)])
def test_rejects_bad_parameters(k, radius):
    with pytest.raises(InvalidInputError):
        thin_uniform(random_sky(10, seed=1), k, radius)
