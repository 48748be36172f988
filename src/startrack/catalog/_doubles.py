"""Double stars: flag close pairs, or merge them into single catalog entries.

Huffman 2006 §5.5.4: stars closer than the optics can resolve become one
catalog entry, with the combined magnitude ``M = M2 - 2.5 log10(1 + 10^((M2 - M1)/2.5))`` and the
flux-weighted direction ``v = sum_i v_i 10^((M - M_i)/2.5)``, normalised (the corrected forms of
the thesis's eqs. "(6.1)" and "(6.2)"). Neighbours are found with a k-d tree on unit vectors,
where an angle theta is the chord ``2 sin(theta / 2)``. Positions are those at the catalog's
epoch; propagate the catalog first to merge at another epoch.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..frames import vector_to_radec
from ._chord import chord_from_angle
from ._star_catalog import StarCatalog


def close_pairs(vectors: NDArray, min_separation_rad: float) -> NDArray[np.int64]:
    """Index pairs (P, 2), i < j, of unit vectors (N, 3) at most ``min_separation_rad`` apart."""
    chord = chord_from_angle(min_separation_rad, "min_separation_rad")
    pairs = cKDTree(vectors).query_pairs(chord, output_type="ndarray")
    return np.asarray(pairs, dtype=np.int64).reshape(-1, 2)


def flag_doubles(catalog: StarCatalog, min_separation_rad: float,
                 max_delta_mag: float = np.inf) -> NDArray[np.bool_]:
    """True (N,) for each star with another star closer than ``min_separation_rad`` (radians).

    With ``max_delta_mag``, a neighbour more than that many magnitudes fainter than a star does
    not flag it (it moves the brighter star's centroid by under its flux ratio times the
    separation: 6 % at 3 mag); the fainter star of such a pair is still flagged.
    """
    flags = np.zeros(len(catalog), dtype=bool)
    pairs = close_pairs(catalog.vectors(), min_separation_rad)
    mag = np.asarray(catalog.v_mag, dtype=float)
    gap = mag[pairs[:, 1]] - mag[pairs[:, 0]]  # > 0: the second star is the fainter
    flags[pairs[:, 0][~(gap > max_delta_mag)]] = True
    flags[pairs[:, 1][~(-gap > max_delta_mag)]] = True
    return flags


def _groups(n: int, pairs: NDArray) -> NDArray[np.int64]:
    """Group label (N,) of each star: connected components of the close-pair graph."""
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def _flux_sum(labels: NDArray, weights: NDArray, n_groups: int) -> NDArray:
    return np.bincount(labels, weights=weights, minlength=n_groups)


def _combined_mag(labels: NDArray, mags: NDArray, n_groups: int) -> NDArray:
    return -2.5 * np.log10(_flux_sum(labels, 10.0 ** (-0.4 * mags), n_groups))


def merge_doubles(catalog: StarCatalog, min_separation_rad: float) -> StarCatalog:
    """One entry per group of stars closer than ``min_separation_rad`` (radians); others kept.

    Groups are the connected components of the "closer than the threshold" graph (union-find,
    friends-of-friends): in a chain A-B-C where A-B and B-C are close, all three merge even if A-C
    is wider than the threshold. Each group becomes one star with:

    - ``v_mag``, ``hp_mag``: magnitude of the summed flux in that band (module docstring);
    - ``b_v``: ``B - V`` of the summed B and V fluxes, NaN if any member lacks a colour;
    - direction: V-flux-weighted sum of the members' unit vectors, normalised;
    - proper motions and parallax: V-flux-weighted means (the photocentre's motion);
    - ``hip``: the brightest member's (in V); ``variable``: true if any member is.

    The output keeps the input order (a group sits where its first member was).
    """
    pairs = close_pairs(catalog.vectors(), min_separation_rad)
    if len(pairs) == 0:
        return catalog
    labels = _groups(len(catalog), pairs)
    _, first = np.unique(labels, return_index=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    labels = rank[labels]  # groups numbered in order of their first member
    return _merge_groups(catalog, labels, len(first))


def _merge_groups(catalog: StarCatalog, labels: NDArray, n_groups: int) -> StarCatalog:
    """Combine the stars of each group ``labels`` (N,) in 0..n_groups-1 (see merge_doubles)."""
    flux = 10.0 ** (-0.4 * catalog.v_mag)
    total = _flux_sum(labels, flux, n_groups)
    v_mag = -2.5 * np.log10(total)

    def mean(values: NDArray) -> NDArray:
        return _flux_sum(labels, flux * values, n_groups) / total

    direction = np.stack([mean(c) for c in catalog.vectors().T], axis=-1)
    ra, dec = vector_to_radec(direction)
    brightest = np.lexsort((catalog.v_mag, labels))
    starts = np.searchsorted(labels[brightest], np.arange(n_groups))
    return StarCatalog(
        hip=catalog.hip[brightest[starts]], ra_rad=ra, dec_rad=dec,
        pm_ra_mas_yr=mean(catalog.pm_ra_mas_yr), pm_dec_mas_yr=mean(catalog.pm_dec_mas_yr),
        parallax_mas=mean(catalog.parallax_mas),
        hp_mag=_combined_mag(labels, catalog.hp_mag, n_groups),
        b_v=_combined_mag(labels, catalog.v_mag + catalog.b_v, n_groups) - v_mag,
        v_mag=v_mag, variable=np.bincount(labels, catalog.variable, n_groups) > 0,
        epoch_jyear=catalog.epoch_jyear, pm_radial_mas_yr=mean(catalog.pm_radial_mas_yr),
    )
