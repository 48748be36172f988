"""The angle method with pivoting on the star-pair directory (Huffman 2006 §5.4.1), and
the shared search pieces: star-set order, row joins, pivoting."""

import itertools

import numpy as np
import pytest
from pair_matcher_lists import CAMERA, PDB, check_identified, check_refused, mirrored, random_false_stars, star_list

from startrack import Status
from startrack.frames import random_rotations
from startrack.identify._angle_pivot import AnglePivotOptions, match_angle_pivot
from startrack.identify._pair_search import SearchContext, consistent_rows, extend_by_angle, join_rows, pivot
from startrack.identify._pyramid import pyramid_triads
from startrack.identify._star_order import further_stars, ordered_star_sets
from startrack.units import ARCSEC, DEG


@pytest.mark.parametrize("size", [1, 2, 3, 4, 5])
def test_star_sets_are_every_combination_brightest_first(size):
    sets = list(ordered_star_sets(size, 9))
    assert sorted(sets) == list(itertools.combinations(range(9), size))
    assert sets[0] == tuple(range(size))


def test_star_sets_generalise_the_pyramid_order():
    assert list(ordered_star_sets(3, 10)) == list(pyramid_triads(10))
    assert list(ordered_star_sets(2, 4)) == [(0, 1), (1, 2), (2, 3), (0, 2), (1, 3), (0, 3)]
    assert further_stars((1, 3), 5) == [0, 2, 4]


def test_join_rows_extends_rows_that_share_the_given_stars():
    table = np.array([[1, 2], [3, 4], [5, 6]])
    cand = np.array([[1, 2, 7], [1, 2, 8], [3, 9, 10], [5, 6, 5]])
    joined = join_rows(table, [0, 1], cand)
    np.testing.assert_array_equal(joined, [[1, 2, 7], [1, 2, 8]])  # (5, 6, 5) repeats a star
    np.testing.assert_array_equal(join_rows(table, [0], cand[:, [0, 2]])[:, 2], [7, 8, 10])


def _true_pattern(rng, count=5):
    """Directory stars (count,) within 6 deg of one another, and their camera vectors at a random attitude."""
    while True:
        a = rng.integers(len(PDB.vectors))
        near = np.flatnonzero(PDB.vectors @ PDB.vectors[a] > np.cos(3 * DEG))
        if near.size >= count:
            stars = np.concatenate([[a], rng.choice(near[near != a], count - 1, replace=False)])
            return stars, random_rotations(rng=rng).apply(PDB.vectors[stars])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pivoting_leaves_the_true_correspondence_alone(seed):
    stars, vec = _true_pattern(np.random.default_rng(seed))
    ctx = SearchContext(vec, PDB, 2 * ARCSEC, 3.0, 0.0)
    table = ctx.pairs_fitting(0, 1)
    assert len(table) > 1 and any(np.array_equal(row, stars[:2]) for row in table)
    table, used = pivot(ctx, table, (0, 1), [2, 3, 4], extend_by_angle, max_pivots=3)
    assert len(used) >= 3
    np.testing.assert_array_equal(table, [stars[list(used)]])


def test_a_mirrored_pivot_star_is_refused_by_its_handedness():
    stars, vec = _true_pattern(np.random.default_rng(4), count=3)
    ctx = SearchContext(vec, PDB, 2 * ARCSEC, 3.0, 0.0)
    assert consistent_rows(ctx, stars[None], (0, 1, 2))[0]
    mirror = SearchContext(vec * [-1.0, 1.0, 1.0], PDB, 2 * ARCSEC, 3.0, 0.0)
    assert not consistent_rows(mirror, stars[None], (0, 1, 2))[0]


@pytest.mark.parametrize("seed", [0, 1, 4])
def test_angle_pivot_identifies_seeded_star_lists(seed):
    stars = star_list(seed)
    check_identified(match_angle_pivot(stars.x, stars.y, CAMERA, PDB), stars)


def test_angle_pivot_refuses_mirrors_false_stars_and_short_lists():
    options = AnglePivotOptions(timeout_s=2.0)
    check_refused(match_angle_pivot(*mirrored(star_list(0)), CAMERA, PDB, options=options))
    check_refused(match_angle_pivot(*random_false_stars(5), CAMERA, PDB, options=options))
    stars = star_list(0)
    assert match_angle_pivot(stars.x[:3], stars.y[:3], CAMERA, PDB).status is Status.TOO_FEW_STARS
