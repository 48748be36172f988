"""FieldStars.around: the catalog stars near a set of directions, as a brute-force search finds them."""

import numpy as np
import pytest

from startrack.identify._field_stars import AROUND_FIRST_K, field_stars
from startrack.units import DEG


@pytest.mark.parametrize(("radius_deg", "centre"), [(0.05, (1.0, 0.2, 0.1)), (0.6, (0.0, 0.0, 1.0)),
                                                    (1.5, (-0.06, -0.87, -0.49))])  # the last in the Milky Way
def test_around_equals_a_brute_force_search(radius_deg, centre):
    stars = field_stars(9.5, 2000.0)
    rng = np.random.default_rng(2)
    directions = np.asarray(centre) / np.linalg.norm(centre) + rng.normal(scale=0.05, size=(40, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    directions[3] = np.nan  # an image star the lens model could not invert
    got = stars.around(directions, radius_deg * DEG)
    cos_angle = stars.vectors @ directions[np.isfinite(directions[:, 0])].T
    want = np.flatnonzero((cos_angle >= np.cos(radius_deg * DEG)).any(axis=1))
    assert np.array_equal(got, want)
    if radius_deg > 1:  # some directions had more stars in reach than the first query fetches
        counts = (cos_angle >= np.cos(radius_deg * DEG)).sum(axis=0)
        assert counts.max() > AROUND_FIRST_K


def test_a_new_process_maps_the_cached_arrays_it_would_build():
    """field_stars keeps its arrays in the user cache: what a later process loads is what it builds."""
    from startrack import cache
    from startrack.catalog import catalog_identity
    from startrack.identify._field_stars import FIELD_STARS_KIND, FIELD_STARS_VERSION, _field_arrays

    field_stars.cache_clear()
    stars = field_stars(6.0, 2031.5)  # builds and saves (or loads what an earlier run saved)
    params = {"max_mag": 6.0, "epoch_jyear": 2031.5, "catalog": catalog_identity()}
    cached = cache.load(FIELD_STARS_KIND, FIELD_STARS_VERSION, params)
    built = _field_arrays(6.0, 2031.5)
    assert cached is not None and set(cached) == set(built) == {"rows", "vectors", "brighter_neighbour_rad"}
    for name, array in built.items():
        assert np.array_equal(cached[name], array), name
    assert np.array_equal(stars.rows, built["rows"]) and np.array_equal(stars.vectors, built["vectors"])
    assert stars.tree.n == len(built["rows"]) and np.array_equal(stars.tree.data, built["vectors"])
