"""Geometry of four-star patterns: edge angles, scale-free edge ratios, canonical star order.

A pattern is four unit vectors. Its six pairwise angles, sorted, divided by the largest, give five
ratios that do not depend on the scale of the image (the focal length) nor on its rotation: the
key under which a pattern is stored and looked up (the idea of tetra3, Brown et al. / ESA, here
with our own database layout and verification). Which image star is which catalog star is then
read off the edges themselves: of the 24 orderings, the one whose six edges agree best.
"""

from __future__ import annotations

import itertools

import numpy as np
from numpy.typing import NDArray

from ..frames import angle_between

EDGE_PAIRS = np.array(list(itertools.combinations(range(4), 2)))
"""The six (i, j) star pairs of a pattern, in a fixed order."""


def pair_angles(vectors: NDArray) -> NDArray[np.float64]:
    """The six pairwise angles (radians) of patterns.

    Parameters
    ----------
    vectors : ndarray, shape (..., 4, 3)
        Unit vectors of the four stars.

    Returns
    -------
    ndarray, shape (..., 6)
        Angles for the pairs in :data:`EDGE_PAIRS` order (stable atan2 form).
    """
    return angle_between(vectors[..., EDGE_PAIRS[:, 0], :], vectors[..., EDGE_PAIRS[:, 1], :])


def edge_ratios(angles: NDArray) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sorted edge ratios and the largest edge of patterns.

    Parameters
    ----------
    angles : ndarray, shape (..., 6)

    Returns
    -------
    ratios : ndarray, shape (..., 5)
        The five smaller angles, ascending, divided by the largest.
    largest : ndarray, shape (...)
        The largest angle (radians).
    """
    ordered = np.sort(angles, axis=-1)
    largest = ordered[..., -1]
    return ordered[..., :5] / largest[..., None], largest


def _permutation_edges() -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    perms = np.array(list(itertools.permutations(range(4))))
    lookup = {tuple(p): k for k, p in enumerate(EDGE_PAIRS.tolist())}
    edges = np.array([[lookup[tuple(sorted((p[i], p[j])))] for i, j in EDGE_PAIRS] for p in perms])
    return perms, edges


PERMUTATIONS, PERMUTED_EDGES = _permutation_edges()
"""All 24 orderings of four stars, and for each the image edge that matches each catalog edge:
if catalog star i is image star ``PERMUTATIONS[p, i]``, catalog edge e (in :data:`EDGE_PAIRS`
order) is image edge ``PERMUTED_EDGES[p, e]``."""


def best_correspondence(image_angles: NDArray, catalog_angles: NDArray) -> tuple[NDArray, NDArray]:
    """The star correspondence under which two patterns' edges agree best.

    Parameters
    ----------
    image_angles : ndarray, shape (6,)
        Edge angles of the image pattern (:data:`EDGE_PAIRS` order), at the trial focal length.
    catalog_angles : ndarray, shape (C, 6)
        Edge angles of C candidate catalog patterns.

    Returns
    -------
    perm : ndarray of int, shape (C, 4)
        For each candidate, the image star that matches catalog star 0..3.
    misfit : ndarray, shape (C,)
        Largest relative edge disagreement after removing a common scale factor.
    """
    permuted = image_angles[PERMUTED_EDGES]  # (24, 6)
    scale = catalog_angles.sum(axis=-1)[:, None] / permuted.sum(axis=-1)[None, :]  # (C, 24)
    misfit = np.max(np.abs(permuted[None] * scale[..., None] - catalog_angles[:, None]), axis=-1)
    misfit = misfit / catalog_angles.max(axis=-1, keepdims=True)
    best = np.argmin(misfit, axis=-1)
    return PERMUTATIONS[best], misfit[np.arange(best.size), best]
