"""errors.require: the value of a field set on success, a RuntimeError naming it otherwise."""

import pytest

from startrack.errors import StartrackError, require


def test_a_set_value_comes_back_itself():
    value = object()
    assert require(value, "the camera") is value
    assert require(0.0, "a zero") == 0.0  # falsy but set


def test_an_unset_value_is_a_bug_named_not_a_usage_error():
    with pytest.raises(RuntimeError, match="the solution's camera is not set") as caught:
        require(None, "the solution's camera")
    assert not isinstance(caught.value, StartrackError)
