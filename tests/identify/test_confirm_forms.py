"""The confirmation's cheaper forms against the ones they replace: the false-match bound from
counts per radius against the bound from squared distances, and an attitude given as a
quaternion or a matrix against the same attitude as a Rotation."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack.identify._confirm import _attitude
from startrack.identify._verify import TEST_RADIUS_FRACTIONS, false_match_bound, false_match_bound_counts


@pytest.mark.parametrize("seed", range(5))
def test_bound_from_counts_equals_bound_from_distances(seed):
    rng = np.random.default_rng(seed)
    radius_px = 3.0
    d2 = (radius_px * rng.uniform(0, 1, rng.integers(0, 12))) ** 2
    counts = [int(np.count_nonzero(d2 <= (f * radius_px) ** 2)) for f in TEST_RADIUS_FRACTIONS]
    args = (30, 40, radius_px, 1024, 1024, 500)
    assert false_match_bound_counts(counts, *args) == false_match_bound(d2, *args)


def test_attitude_forms_give_one_matrix():
    rot = Rotation.random(random_state=3)
    for given in (rot, rot.as_quat(), rot.as_matrix()):
        matrix = _attitude(given)
        np.testing.assert_allclose(matrix, rot.as_matrix(), atol=1e-14)  # dimensionless matrix entries
    with pytest.raises(ValueError, match="quaternion"):
        _attitude(np.zeros(3))
