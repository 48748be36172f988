"""Pattern geometry: scale and rotation invariance of the key, and the star correspondence."""

import numpy as np
from scipy.spatial.transform import Rotation

from startrack.frames import normalize
from startrack.identify._patterns import PERMUTATIONS, best_correspondence, edge_ratios, pair_angles
from startrack.units import DEG


def _pattern(rng, size_rad):
    offsets = rng.uniform(-size_rad, size_rad, (4, 2))
    return normalize(np.column_stack([offsets, np.ones(4)]))


def test_ratios_do_not_change_under_rotation():
    rng = np.random.default_rng(1)
    vec = _pattern(rng, 5 * DEG)
    rot = Rotation.random(random_state=2)
    r1, big1 = edge_ratios(pair_angles(vec))
    r2, big2 = edge_ratios(pair_angles(rot.apply(vec)))
    np.testing.assert_allclose(r1, r2, atol=1e-12)
    np.testing.assert_allclose(big1, big2, atol=1e-12)
    assert np.all(np.diff(r1) >= 0) and r1[-1] <= 1.0


def test_ratios_are_nearly_scale_free_for_small_patterns():
    rng = np.random.default_rng(3)
    offsets = rng.uniform(-1, 1, (4, 2))
    small = normalize(np.column_stack([offsets * 0.001, np.ones(4)]))
    smaller = normalize(np.column_stack([offsets * 0.0005, np.ones(4)]))
    np.testing.assert_allclose(edge_ratios(pair_angles(small))[0], edge_ratios(pair_angles(smaller))[0], atol=1e-6)


def test_best_correspondence_recovers_a_shuffle():
    rng = np.random.default_rng(4)
    catalog = _pattern(rng, 3 * DEG)
    for p in rng.permutation(len(PERMUTATIONS))[:8]:
        perm = PERMUTATIONS[p]
        image = np.empty_like(catalog)
        image[perm] = catalog  # catalog star i is image star perm[i]
        found, misfit = best_correspondence(pair_angles(image), pair_angles(catalog)[None])
        assert np.array_equal(found[0], perm)
        assert misfit[0] < 1e-12
