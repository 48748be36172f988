"""The four-star pattern batches of the lost-in-space search: the combinations of its
definition, in its order, shared between star counts."""

import itertools

import numpy as np
import pytest

from startrack.identify import _quad_matcher as quad_matcher


def _by_definition(n: int, first_new: int) -> list[np.ndarray]:
    """The batches as pattern_batches' docstring defines them, through itertools."""
    first = min(n, quad_matcher.FIRST_BATCH_STARS) if first_new == 0 else first_new
    batches = [list(itertools.combinations(range(first), 4))] if first_new == 0 and first >= 4 else []
    for last in range(max(first, 3), n):
        batches.append([(*head, last) for head in itertools.combinations(range(last), 3)])
    return [np.array(b, dtype=np.int64).reshape(-1, 4) for b in batches]


@pytest.mark.parametrize("n", [0, 3, 4, 5, 6, 7, 12, 20, 27])
def test_batches_are_the_defined_combinations_in_order(n):
    for first_new in range(n + 1):
        got = quad_matcher.pattern_batches(n, first_new)
        want = _by_definition(n, first_new)
        assert len(got) == len(want), (n, first_new)
        for g, w in zip(got, want, strict=True):
            assert g.dtype == np.int64 and not g.flags.writeable
            np.testing.assert_array_equal(g, w)


def test_a_new_star_count_reuses_the_batches_built():
    quad_matcher.pattern_batches(20, 0)
    built = quad_matcher._ending_at.cache_info().currsize
    for n in range(4, 20):
        for first_new in (0, n // 2):
            quad_matcher.pattern_batches(n, first_new)
    assert quad_matcher._ending_at.cache_info().currsize == built


def test_combinations_of_too_few_are_empty():
    assert quad_matcher._combinations(2, 3).shape == (0, 3)
