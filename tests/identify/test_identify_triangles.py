"""Triangle matching by area and polar moment, planar and spherical (Cole & Crassidis; Huffman 2006
§5.4.2): the features against known values, their errors against Monte Carlo,
the triangle directory, and the matcher."""

import math

import numpy as np
import pytest
from pair_matcher_lists import CAMERA, PDB, check_identified, check_refused, mirrored, random_false_stars, star_list

from startrack.errors import InvalidInputError
from startrack.frames import angle_between, normalize, random_rotations
from startrack.identify._pair_search import SearchContext
from startrack.identify._triangle_database import directory_triangles, load_triangle_database
from startrack.identify._triangle_features import (
    feature_sigmas,
    lhuilier_area,
    planar_features,
    spherical_features,
    subdivide,
)
from startrack.identify._triangles import TriangleOptions, match_triangles, triangle_candidates
from startrack.units import ARCSEC, DEG

RNG_TRIANGLE = normalize(np.array([[0.0, 0.0, 1.0], [0.05, 0.01, 1.0], [0.02, 0.07, 1.0]]))
"""A triangle of about 3 x 4 deg."""


def test_planar_area_and_moment_of_a_right_triangle():
    # legs 3 and 4: area 6, polar moment about the centroid b h (b^2 + h^2) / 36
    area, moment = planar_features(np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 4.0, 0.0]]))
    assert area == pytest.approx(6.0, rel=1e-14)
    assert moment == pytest.approx(3 * 4 * (9 + 16) / 36, rel=1e-14)


def test_heron_area_of_a_thin_triangle_equals_the_cross_product_area():
    tri = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.3, 1e-4, 0.0]])  # sides sum to 1 + 2e-8
    assert planar_features(tri)[0] == pytest.approx(0.5e-4, rel=1e-7)


def test_lhuilier_area_of_the_octant_and_girards_excess():
    assert lhuilier_area(np.eye(3)) == pytest.approx(math.pi / 2, rel=1e-14)
    tri = normalize(np.array([[1.0, 0.2, 0.1], [0.1, 1.0, 0.3], [0.2, 0.1, 1.0]]))
    corners = []  # interior angles from the tangents of the two sides at each vertex
    for i in range(3):
        a, b, c = tri[i], tri[(i + 1) % 3], tri[(i + 2) % 3]
        corners.append(angle_between(b - (a @ b) * a, c - (a @ c) * a))
    assert lhuilier_area(tri) == pytest.approx(sum(corners) - math.pi, rel=1e-12)


def test_subdivision_covers_the_triangle():
    sub = subdivide(RNG_TRIANGLE, 3)
    assert sub.shape == (64, 3, 3)
    assert np.sum(lhuilier_area(sub)) == pytest.approx(lhuilier_area(RNG_TRIANGLE), rel=1e-12)


def test_spherical_moment_of_the_octant_against_monte_carlo():
    rng = np.random.default_rng(0)
    points = normalize(np.abs(rng.normal(size=(400_000, 3))))  # uniform in the octant
    theta = angle_between(points, normalize(np.ones(3)))
    reference = math.pi / 2 * np.mean(theta**2)  # standard error 0.05 %
    _, moment = spherical_features(np.eye(3), levels=6)
    assert moment == pytest.approx(reference, rel=3e-3)


def test_spherical_features_of_a_small_triangle_tend_to_the_planar_ones():
    small = normalize(np.array([[0.0, 0.0, 1.0], [0.005, 0.001, 1.0], [0.002, 0.007, 1.0]]))
    planar, spherical = planar_features(small), spherical_features(small, levels=5)
    assert spherical[0] == pytest.approx(planar[0], rel=1e-4)
    assert spherical[1] == pytest.approx(planar[1], rel=2e-3)  # the subdivision falls short by ~4**-5


@pytest.mark.parametrize("variant", ["planar", "spherical"])
def test_linearised_feature_errors_match_monte_carlo(variant):
    sigma = 20 * ARCSEC
    rng = np.random.default_rng(1)
    noisy = normalize(RNG_TRIANGLE + rng.normal(0, sigma, (3000, 3, 3)))
    area, moment = (planar_features(noisy) if variant == "planar" else spherical_features(noisy))
    sigma_area, sigma_moment = feature_sigmas(RNG_TRIANGLE, sigma, variant)
    assert sigma_area == pytest.approx(np.std(area), rel=0.08)
    assert sigma_moment == pytest.approx(np.std(moment), rel=0.08)


def test_directory_triangles_are_the_closed_triples_of_the_pairs():
    pairs = np.array([[0, 1], [2, 1], [0, 2], [2, 3], [1, 3], [3, 4], [4, 0]])
    np.testing.assert_array_equal(directory_triangles(pairs), [[0, 1, 2], [1, 2, 3]])


@pytest.mark.parametrize("variant", ["planar", "spherical"])
def test_the_true_triangle_is_a_candidate_and_its_mirror_is_not(variant):
    tdb = load_triangle_database(PDB, variant)
    assert np.all(np.diff(tdb.area) >= 0) and len(tdb.triangles) == len(tdb.moment)
    rng = np.random.default_rng(3)
    for row in rng.choice(len(tdb.triangles), 5, replace=False):
        stars = tdb.triangles[row][rng.permutation(3)]
        vec = random_rotations(rng=rng).apply(PDB.vectors[stars])
        found = triangle_candidates(tdb, SearchContext(vec, PDB, 1 * ARCSEC, 3.0, 0.0), (0, 1, 2))
        assert any(np.array_equal(t, stars) for t in found)
        mirror = SearchContext(vec * [-1.0, 1.0, 1.0], PDB, 1 * ARCSEC, 3.0, 0.0)
        assert not any(np.array_equal(t, stars) for t in triangle_candidates(tdb, mirror, (0, 1, 2)))
    assert tdb.area[-1] < (22 * DEG) ** 2  # only triangles that fit the directory's field


@pytest.mark.parametrize("variant", ["planar", "spherical"])
@pytest.mark.parametrize("seed", [0, 5])
def test_triangles_identify_seeded_star_lists(seed, variant):
    stars = star_list(seed)
    check_identified(match_triangles(stars.x, stars.y, CAMERA, PDB, variant=variant), stars)


@pytest.mark.parametrize("variant", ["planar", "spherical"])
def test_triangles_refuse_mirrors_and_false_stars(variant):
    options = TriangleOptions(timeout_s=2.0)
    check_refused(match_triangles(*mirrored(star_list(1)), CAMERA, PDB, options=options, variant=variant))
    check_refused(match_triangles(*random_false_stars(6), CAMERA, PDB, options=options, variant=variant))


def test_unknown_variant_is_misuse():
    stars = star_list(0)
    with pytest.raises(InvalidInputError, match="variant"):
        match_triangles(stars.x, stars.y, CAMERA, PDB, variant="conic")
