"""The n-vertex match (Huffman 2006 §5.5.4 pp.111-113, Table 5.4): C and S matrices, the
self-consistency check, and the matcher for n = 3, 4, 5."""

import numpy as np
import pytest
from pair_matcher_lists import CAMERA, PDB, check_identified, check_refused, mirrored, random_false_stars, star_list

from startrack.errors import InvalidInputError
from startrack.frames import random_rotations
from startrack.identify._nvertex import (
    NVertexOptions,
    SMatrix,
    baselines,
    consistent_ngons,
    match_nvertex,
    ngon_candidates,
)
from startrack.identify._pair_search import SearchContext
from startrack.units import ARCSEC, DEG

TABLE_5_4_C = [np.array([[45, 46]]), np.array([[45, 47]]), np.array([[45, 48]]),
               np.array([[46, 47]]), np.array([[46, 48]]), np.array([[47, 48]])]
"""The C matrix behind Huffman 2006 Table 5.4: one catalog pair per baseline AB, AC, AD, BC, BD, CD."""


def test_baselines_are_numbered_as_in_the_seed():
    assert baselines(4) == [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]  # AB AC AD BC BD CD
    assert len(baselines(5)) == 10


def test_s_matrix_rows_of_table_5_4():
    s = SMatrix(TABLE_5_4_C)
    assert s.row(45) == [{46}, {47}, {48}, set(), set(), set()]
    assert s.row(46) == [{45}, set(), set(), {47}, {48}, set()]
    assert s.row(47) == [set(), {45}, set(), {46}, set(), {48}]
    assert s.row(48) == [set(), set(), {45}, set(), {46}, {47}]  # C's columns are {2, 4, 6}, not {4, 5, 6}
    assert s.contains(np.array([46, 46]), np.array([48, 47]), 4).tolist() == [True, False]


def test_self_consistency_finds_a_b_c_d_of_table_5_4_among_decoys():
    assert consistent_ngons(TABLE_5_4_C, 4).tolist() == [[45, 46, 47, 48]]
    decoys = [np.array([[45, 46], [12, 45], [46, 30]]), np.array([[45, 47], [12, 31], [45, 33]]),
              np.array([[45, 48], [12, 48], [33, 50]]), np.array([[46, 47], [46, 31], [30, 47]]),
              np.array([[46, 48], [48, 30]]), np.array([[47, 48], [31, 48]])]
    assert consistent_ngons(decoys, 4).tolist() == [[45, 46, 47, 48]]
    decoys[5] = np.array([[31, 48]])  # without C-D the quadrilateral is gone
    assert consistent_ngons(decoys, 4).shape == (0, 4)
    assert consistent_ngons([decoys[0], decoys[1], decoys[3]], 3).tolist() == [[45, 46, 47]]  # AB AC BC


@pytest.mark.parametrize("n", [3, 4, 5])
def test_the_true_ngon_passes_and_its_mirror_does_not(n):
    rng = np.random.default_rng(n)
    for _ in range(3):
        a = rng.integers(len(PDB.vectors))
        near = np.flatnonzero(PDB.vectors @ PDB.vectors[a] > np.cos(4 * DEG))
        if near.size < n:
            continue
        stars = np.concatenate([[a], rng.choice(near[near != a], n - 1, replace=False)])
        vec = random_rotations(rng=rng).apply(PDB.vectors[stars])
        found = ngon_candidates(SearchContext(vec, PDB, 1 * ARCSEC, 3.0, 0.0), tuple(range(n)))
        assert any(np.array_equal(row, stars) for row in found)
        mirror = ngon_candidates(SearchContext(vec * [-1.0, 1.0, 1.0], PDB, 1 * ARCSEC, 3.0, 0.0), tuple(range(n)))
        assert not any(np.array_equal(row, stars) for row in mirror)


@pytest.mark.parametrize("n", [3, 4, 5])
@pytest.mark.parametrize("seed", [0, 6])
def test_nvertex_identifies_seeded_star_lists(seed, n):
    stars = star_list(seed)
    check_identified(match_nvertex(stars.x, stars.y, CAMERA, PDB, n=n), stars)


@pytest.mark.parametrize("n", [3, 5])
def test_nvertex_refuses_mirrors_and_false_stars(n):
    options = NVertexOptions(timeout_s=2.0)
    check_refused(match_nvertex(*mirrored(star_list(2)), CAMERA, PDB, options=options, n=n))
    check_refused(match_nvertex(*random_false_stars(7), CAMERA, PDB, options=options, n=n))


def test_unsupported_n_is_misuse():
    stars = star_list(0)
    with pytest.raises(InvalidInputError, match="n must be"):
        match_nvertex(stars.x, stars.y, CAMERA, PDB, n=6)
