"""What solve_stars takes as a star list: real numbers in one dimension. Before, None gave
"NaN or inf", a (N, 2) table was flattened into a list of the wrong numbers, and complex numbers
lost their imaginary part with only numpy's ComplexWarning."""

from __future__ import annotations

import numpy as np
import pytest

from startrack import solve_stars
from startrack.errors import InvalidInputError


@pytest.mark.parametrize(("x", "said"), [
    (None, "got None"),
    (np.ones((3, 2)), "shape (3, 2)"),
    (np.ones(3) + 1j, "real numbers"),
])
def test_a_star_list_that_is_not_real_numbers_in_one_dimension_is_refused(x, said):
    with pytest.raises(InvalidInputError, match=r"x must be real numbers in one dimension") as info:
        solve_stars(x, [1.0, 2.0, 3.0], width=10, height=10)
    assert said in str(info.value)


@pytest.mark.parametrize("x", [[1, 2, 3], np.float32([1, 2, 3]), np.ma.array([1.0, 2.0, 3.0]),
                               np.array([[1.0], [2.0], [3.0]]), np.array([[1.0, 2.0, 3.0]])])
def test_lists_arrays_and_unmasked_arrays_of_numbers_are_taken(x):
    solution = solve_stars(x, [1.0, 2.0, 3.0], width=10, height=10)
    assert not solution.solved  # three stars: too few, but read
