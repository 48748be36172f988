"""Verification: nearest matching and the false-match probability bound."""

import numpy as np
from scipy.stats import binom

from startrack.identify._verify import false_match_bound, false_match_probability, match_nearest


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


def test_bound_takes_the_better_radius_and_pays_for_two():
    radius = 3.0
    close = np.full(3, (0.4 * radius) ** 2)  # every extra star within half the radius
    wide = np.full(3, (0.8 * radius) ** 2)  # every extra star between half and the whole radius
    at_full = false_match_probability(3, 6, 20, radius, 1024, 1024, 5)
    at_half = false_match_probability(3, 6, 20, radius / 2, 1024, 1024, 5)
    assert np.isclose(false_match_bound(close, 6, 20, radius, 1024, 1024, 5), 2 * at_half, rtol=1e-12)
    assert np.isclose(false_match_bound(wide, 6, 20, radius, 1024, 1024, 5), 2 * at_full, rtol=1e-12)
    assert false_match_bound(np.zeros(0), 6, 20, radius, 1024, 1024, 5) == 1.0


def test_bound_holds_its_level_for_wrong_attitudes():
    """Monte Carlo: image stars and predicted stars placed independently (a wrong attitude). The
    share of fields whose bound is at or below a level must not exceed that level."""
    rng = np.random.default_rng(3)
    size, n_img, n_pred, radius, level = 1024.0, 12, 60, 40.0, 0.02
    passed = 0
    n_fields = 4000
    for _ in range(n_fields):
        img = rng.uniform(0.0, size, (n_img, 2))
        pred = rng.uniform(0.0, size, (n_pred, 2))
        i, c = match_nearest(img[:, 0], img[:, 1], pred[:, 0], pred[:, 1], radius)
        d2 = ((img[i] - pred[c]) ** 2).sum(axis=1)
        passed += false_match_bound(d2, n_img, n_pred, radius, int(size), int(size), 1) <= level
    assert passed / n_fields <= level  # binomial sampling spread at 4000 fields: about 0.002
