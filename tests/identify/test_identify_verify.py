"""Verification: nearest matching and the false-match probability bound."""

import numpy as np
from scipy.stats import binom

from startrack.identify.verify import false_match_probability, match_nearest


def test_probability_is_the_binomial_tail_times_trials():
    p_single = 30 * np.pi * 3.0**2 / (1024 * 1024)
    expected = 5 * binom.sf(6 - 1, 20, p_single)
    got = false_match_probability(6, 20, 30, 3.0, 1024, 1024, n_trials=5)
    assert np.isclose(got, expected, rtol=1e-10)


def test_probability_falls_with_matches_and_rises_with_radius():
    base = false_match_probability(5, 20, 30, 3.0, 1024, 1024, 10)
    assert false_match_probability(8, 20, 30, 3.0, 1024, 1024, 10) < base
    assert false_match_probability(5, 20, 30, 6.0, 1024, 1024, 10) > base
    assert false_match_probability(0, 20, 30, 3.0, 1024, 1024, 10) == 1.0


def test_match_nearest_uses_each_star_once_nearest_first():
    img_x, img_y = np.array([0.0, 1.0, 50.0]), np.zeros(3)
    cat_x, cat_y = np.array([0.4, 80.0]), np.zeros(2)
    i, c = match_nearest(img_x, img_y, cat_x, cat_y, radius_px=2.0)
    assert i.tolist() == [0] and c.tolist() == [0]
