"""errors.require: the value of a field set on success, a RuntimeError naming it otherwise."""

import pytest

from startrack.errors import InvalidInputError, StartrackError, require


def test_a_set_value_comes_back_itself():
    value = object()
    assert require(value, "the camera") is value
    assert require(0.0, "a zero") == 0.0  # falsy but set


def test_an_unset_value_is_a_bug_named_not_a_usage_error():
    with pytest.raises(RuntimeError, match="the solution's camera is not set") as caught:
        require(None, "the solution's camera")
    assert not isinstance(caught.value, StartrackError)


def test_checked_number_and_count_name_the_argument_and_the_range():
    from startrack.errors import checked_count, checked_number

    assert checked_number(3, "x", low=0.0) == 3.0 and checked_number(10**30, "x") == 1e30
    for bad in ("1", None, True, float("nan"), float("inf"), 10**400, -1.0):
        with pytest.raises(InvalidInputError, match="^k must be a finite number >= 0 and <= 5, got "):
            checked_number(bad, "k", low=0.0, high=5.0)
    with pytest.raises(InvalidInputError, match="^k must be a finite number > 0, got 0"):
        checked_number(0, "k", low=0.0, above_low=True)
    assert checked_count(3, "n", 1) == 3
    for bad in (0, 2.0, True, "3", 10**30):
        with pytest.raises(InvalidInputError, match="^n must be an integer >= 1 and <= 100, got "):
            checked_count(bad, "n", 1, 100)
