"""How far a streak fit may follow its ends (startrack.rate.fit_streaks' max_windows): a fit from a
first guess that is too short moves its window to the true ends, unless it is held to the window
around its guess, as the fits of predicted streaks are (a prediction it walks away from cannot
agree with it)."""

import numpy as np
import pytest

from startrack.errors import InvalidInputError
from startrack.rate import fit_streaks
from startrack.rate._streak_kernel import NGEO, arc_value, geometry

SIZE, NOISE = 160, 5.0
TRUTH = np.array([80.0, 80.0, 50.0, 20.0, 0.0, 400.0, 0.0, 100.0, 1.2])
"""(cx, cy, hx, hy, sag, a, g, b, s): a bright straight streak 108 px long."""


def _image(seed: int = 0) -> np.ndarray:
    geo = np.empty(NGEO)
    geometry(TRUTH, geo)
    model = np.array([[arc_value(float(x), float(y), geo) for x in range(SIZE)] for y in range(SIZE)])
    return model + np.random.default_rng(seed).normal(0.0, NOISE, model.shape)


def _short_guess() -> np.ndarray:
    guess = TRUTH.copy()
    guess[2:4] *= 0.6  # ends 22 px short of the truth on each side
    return guess[None, :]


def _end_error_px(fits) -> float:
    truth = np.array([TRUTH[0:2] - TRUTH[2:4], TRUTH[0:2] + TRUTH[2:4]])
    ends = fits.ends_xy[0]
    return float(min(np.abs(ends - truth).max(), np.abs(ends[::-1] - truth).max()))


def test_a_short_guess_follows_its_ends_through_windows():
    reach, band = np.array([8.0]), np.array([6.0])
    fits = fit_streaks(_image(), _short_guess(), reach, band, noise=NOISE, passes=1, max_windows=3)
    assert _end_error_px(fits) < 0.5  # px: the true ends are found


def test_a_fit_held_to_its_window_cannot_reach_the_true_ends():
    reach, band = np.array([8.0]), np.array([6.0])
    fits = fit_streaks(_image(), _short_guess(), reach, band, noise=NOISE, passes=1, max_windows=1)
    assert _end_error_px(fits) > 5.0  # px: its window holds no pixel of the true ends (measured: 10.5 px)


@pytest.mark.parametrize("bad", [0, -1, 1.5, "3"])
def test_max_windows_is_a_positive_whole_number(bad):
    with pytest.raises(InvalidInputError, match="max_windows"):
        fit_streaks(_image(), _short_guess(), [8.0], [6.0], noise=NOISE, max_windows=bad)


def test_a_fit_out_of_iterations_is_refused_and_one_with_enough_is_not():
    reach, band = np.array([8.0]), np.array([6.0])
    guess = TRUTH.copy()
    guess[0] += 1.5  # px off along x: several steps from the truth
    short = fit_streaks(_image(), guess[None], reach, band, noise=NOISE, passes=1, max_iter=1)
    enough = fit_streaks(_image(), guess[None], reach, band, noise=NOISE, passes=1, max_iter=10)
    assert short.reasons == ("the fit did not converge",) and not short.ok[0]
    assert enough.ok[0] and _end_error_px(enough) < 0.5  # px


@pytest.mark.parametrize("bad", [0, -2, 2.5, None, True])
def test_max_iter_is_a_positive_whole_number(bad):
    with pytest.raises(InvalidInputError, match="max_iter"):
        fit_streaks(_image(), _short_guess(), [8.0], [6.0], noise=NOISE, max_iter=bad)
