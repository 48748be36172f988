"""Degenerate problems give a status; misuse raises InvalidInputError."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from wahba_problems import angle_rad, problems, random_unit_vectors

from startrack.attitude import solve_wahba
from startrack.errors import InvalidInputError
from startrack.results import Status
from startrack.units import RAD

METHODS = ["quest", "qmethod"]
X, Y, Z = np.eye(3)


def _degenerate_cases():
    v = np.array([0.3, -0.5, 0.8])
    return {
        "one vector": (v[None], v[None], None),
        "no vector": (np.zeros((0, 3)), np.zeros((0, 3)), None),
        "parallel": (np.tile(v, (4, 1)), np.tile(v, (4, 1)) * [[1], [2], [3], [4]], None),
        "antiparallel": (np.array([X, -X, X]), np.array([Y, -Y, Y]), None),
        "parallel observed only": (np.array([X, X]), np.array([X, Y]), None),
        "one weighted vector": (np.array([X, Y, Z]), np.array([X, Y, Z]), [0.0, 2.0, 0.0]),
        "within a micro-radian": (
            np.array([X, X + [0, 2e-7, 0]]),
            np.array([Y, Y + [3e-7, 0, 0]]),
            None,
        ),
    }


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("case", list(_degenerate_cases()))
def test_degenerate_problem_gives_status_not_exception(method, case):
    observed, reference, weights = _degenerate_cases()[case]
    result = solve_wahba(observed, reference, weights, method=method, sigma_rad=0.001)
    assert result.status is Status.DEGENERATE
    assert not result.ok
    assert "non-parallel" in result.reason
    assert result.rotation is None and result.covariance_rad2 is None and np.isnan(result.loss)


@pytest.mark.parametrize("method", METHODS)
def test_degenerate_slot_in_a_batch(method):
    rng = np.random.default_rng(20)
    truth = Rotation.random(3, random_state=rng)
    reference = random_unit_vectors((3, 4), rng)
    observed = problems(truth, reference, 0.0, rng)
    reference[1] = np.tile(reference[1, 0], (4, 1))  # problem 1: all parallel
    result = solve_wahba(observed, reference, method=method, sigma_rad=0.01)
    assert list(result.status) == [Status.OK, Status.DEGENERATE, Status.OK]
    assert list(result.ok) == [True, False, True]
    assert result.reason[0] == "" and "non-parallel" in result.reason[1]
    assert angle_rad(result.rotation[1], Rotation.identity()) == 0.0  # placeholder
    assert np.isnan(result.loss[1]) and np.all(np.isnan(result.covariance_rad2[1]))
    good = [0, 2]
    assert np.max(angle_rad(result.rotation[good], truth[good])) < 1e-9 * RAD
    assert np.all(np.isfinite(result.covariance_rad2[good]))


def test_two_separated_vectors_are_not_degenerate():
    observed = np.array([X, X + [0, 1e-5, 0]])
    reference = np.array([Y, Y + [1e-5, 0, 0]])
    assert solve_wahba(observed, reference).status is Status.OK


def test_no_sigma_no_covariance():
    result = solve_wahba(np.array([X, Y]), np.array([Y, Z]))
    assert result.status is Status.OK and result.covariance_rad2 is None


GOOD = np.array([X, Y, Z])


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"observed": GOOD[:, :2]}, "observed must have shape"),
        ({"observed": GOOD[None, None]}, "observed must have shape"),
        ({"observed": np.zeros((0, 3, 3))}, "at least one problem"),
        ({"reference": GOOD[:2]}, "same shape"),
        ({"reference": GOOD[None]}, "same shape"),
        ({"observed": np.array([X, Y, [np.nan, 0, 1]])}, "finite"),
        ({"reference": np.array([X, Y, [0.0, 0, 0]])}, "zero-length"),
        ({"weights": [1.0, 2.0]}, "weights must be a scalar or have shape"),
        ({"weights": [1.0, -2.0, 1.0]}, "non-negative"),
        ({"weights": [1.0, np.inf, 1.0]}, "non-negative"),
        ({"sigma_rad": [1e-5, 0.0, 1e-5]}, "positive"),
        ({"sigma_rad": np.ones((2, 3))}, "sigma_rad must be a scalar or have shape"),
        ({"method": "triad-ish"}, "method must be one of quest, qmethod"),
        # these three reached numpy: "could not convert string to float", TypeError, "Eigenvalues did not converge"
        ({"observed": "x"}, "observed must be a number or an array of numbers, got 'x'"),
        ({"weights": {}}, "weights must be a number or an array of numbers, got {}"),
        ({"sigma_rad": 1e-300}, "sigma_rad must be at least 1e-150 rad"),
    ],
)
def test_bad_input_raises_invalid_input_error(kwargs, words):
    arguments = {"observed": GOOD, "reference": GOOD} | kwargs
    with pytest.raises(InvalidInputError, match=words):
        solve_wahba(**arguments)


def test_invalid_input_error_is_a_value_error():
    with pytest.raises(ValueError, match="observed"):
        solve_wahba(GOOD[:, :2], GOOD[:, :2])


def test_batched_weights_may_be_shared_or_per_problem():
    rng = np.random.default_rng(21)
    reference = random_unit_vectors((5, 4), rng)
    observed = problems(Rotation.random(5, random_state=rng), reference, 0.01, rng)
    shared = solve_wahba(observed, reference, [1.0, 2.0, 3.0, 4.0])
    per_problem = solve_wahba(observed, reference, np.tile([1.0, 2.0, 3.0, 4.0], (5, 1)))
    assert np.max(angle_rad(shared.rotation, per_problem.rotation)) == 0.0
    with pytest.raises(InvalidInputError, match=r"\(4,\) or \(5, 4\)"):
        solve_wahba(observed, reference, np.ones((4, 4)))
