"""Campaign statistics against independent references: the Wilson interval against its formula in
mpmath and a published value, the false-solve bound against scipy's beta and binomial
distributions, percentiles against numpy, and the AGG:COLUMN metric language."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from scipy import stats

from startrack.analysis.campaign._stats import Metric, parse_metric, percentiles, rate_upper_bound, rms, wilson_interval
from startrack.errors import InvalidInputError


def wilson_mpmath(k: int, n: int, confidence: float) -> tuple[float, float]:
    """The Wilson score interval evaluated at 40 digits: z from the inverse error function."""
    mpmath.mp.dps = 40
    z = mpmath.sqrt(2) * mpmath.erfinv(mpmath.mpf(confidence))
    p = mpmath.mpf(k) / n
    centre = (p + z**2 / (2 * n)) / (1 + z**2 / n)
    half = z / (1 + z**2 / n) * mpmath.sqrt(p * (1 - p) / n + z**2 / (4 * n**2))
    return float(centre - half), float(centre + half)


def test_wilson_published_value_n10_k0():
    # Brown, Cai & DasGupta (2001) / the usual tables: 0 of 10 gives [0, 0.2775] at 95 %
    low, high = wilson_interval(0, 10)
    assert low == 0.0
    assert high == pytest.approx(0.2775, abs=5e-5)


@pytest.mark.parametrize(("k", "n", "confidence"), [(0, 1, 0.95), (3, 10, 0.95), (7, 10, 0.9), (50, 100, 0.99),
                                                    (999, 1000, 0.95), (1, 200, 0.6827), (20, 20, 0.95)])
def test_wilson_matches_the_formula_in_mpmath(k, n, confidence):
    low, high = wilson_interval(k, n, confidence)
    ref_low, ref_high = wilson_mpmath(k, n, confidence)
    assert low == pytest.approx(max(ref_low, 0.0), abs=1e-12)
    assert high == pytest.approx(min(ref_high, 1.0), abs=1e-12)


def test_wilson_is_symmetric_and_contains_the_rate():
    for k in range(0, 31, 3):
        low, high = wilson_interval(k, 30)
        mlow, mhigh = wilson_interval(30 - k, 30)
        assert low == pytest.approx(1 - mhigh, abs=1e-12) and high == pytest.approx(1 - mlow, abs=1e-12)
        assert low <= k / 30 <= high


def test_wilson_without_trials_is_nan_and_bad_counts_are_refused():
    assert all(math.isnan(v) for v in wilson_interval(0, 0))
    with pytest.raises(InvalidInputError, match="0 <= k <= n"):
        wilson_interval(5, 4)
    with pytest.raises(InvalidInputError, match="confidence"):
        wilson_interval(1, 4, confidence=1.0)


def test_the_exact_bound_when_nothing_was_seen_is_the_rule_of_three_for_large_n():
    for n, confidence in ((3, 0.95), (100, 0.95), (1000, 0.99)):
        bound = rate_upper_bound(0, n, confidence)
        assert bound == pytest.approx(1 - (1 - confidence) ** (1 / n), rel=1e-12)
        assert bound == pytest.approx(stats.beta.ppf(confidence, 1, n), rel=1e-9)
    assert rate_upper_bound(0, 100_000) == pytest.approx(3 / 100_000, rel=0.002)  # 2.996 / n
    assert rate_upper_bound(0, 1) == pytest.approx(0.95, rel=1e-12)
    assert math.isnan(rate_upper_bound(0, 0))


@pytest.mark.parametrize("n", [2, 3, 4, 10, 30, 1000])
def test_seeing_a_false_solve_never_lowers_the_bound(n):
    """With the rule of three at k = 0, n = 3 gave 1.0 for none seen and 0.865 for one."""
    bounds = [rate_upper_bound(k, n) for k in range(n + 1)]
    assert all(a < b for a, b in zip(bounds, bounds[1:], strict=False))


@pytest.mark.parametrize(("k", "n", "confidence"), [(1, 100, 0.95), (5, 50, 0.95), (17, 1000, 0.99), (3, 8, 0.9)])
def test_clopper_pearson_upper_bound(k, n, confidence):
    bound = rate_upper_bound(k, n, confidence)
    assert bound == pytest.approx(stats.beta.ppf(confidence, k + 1, n - k), rel=1e-12)
    # its meaning, independently: at the bound, seeing k or fewer events has probability 1 - confidence
    assert stats.binom.cdf(k, n, bound) == pytest.approx(1 - confidence, rel=1e-6)
    assert rate_upper_bound(n, n, confidence) == 1.0


def test_percentiles_match_numpy_and_ignore_nan():
    rng = np.random.default_rng(5)
    values = rng.lognormal(size=1001)
    with_nan = np.concatenate([values, [np.nan, np.inf]])
    np.testing.assert_allclose(percentiles(with_nan), np.percentile(values, [50, 68, 95, 99.7]), rtol=1e-14)
    np.testing.assert_allclose(percentiles(values, (0, 100)), [values.min(), values.max()], rtol=1e-14)
    assert np.isnan(percentiles([np.nan], (50, 95))).all()
    with pytest.raises(InvalidInputError, match=r"\[0, 100\]"):
        percentiles(values, (50, 101))


def test_rms():
    assert rms([3.0, -4.0, np.nan]) == pytest.approx(math.sqrt(12.5), rel=1e-14)
    assert math.isnan(rms([]))


@pytest.mark.parametrize(("text", "agg", "column", "q", "absolute", "rows"), [
    ("p95:err_cross_arcsec", "percentile", "err_cross_arcsec", 95.0, False, "correct"),
    ("p99.7:err_total_arcsec", "percentile", "err_total_arcsec", 99.7, False, "correct"),
    ("abs95:err_roll_arcsec", "percentile", "err_roll_arcsec", 95.0, True, "correct"),
    ("absp50:err_roll_arcsec", "percentile", "err_roll_arcsec", 50.0, True, "correct"),
    ("absmedian:err_x_arcsec", "median", "err_x_arcsec", None, True, "correct"),
    ("rate:correct", "rate", "correct", None, False, "all"),
    ("min:n_stars", "min", "n_stars", None, False, "all"),
    ("rms:err_y_arcsec@solved", "rms", "err_y_arcsec", None, False, "solved"),
    ("median:err_total_arcsec@all", "median", "err_total_arcsec", None, False, "all"),
])
def test_parse_metric(text, agg, column, q, absolute, rows):
    m = parse_metric(text)
    assert (m.agg, m.column, m.q, m.absolute, m.rows) == (agg, column, q, absolute, rows)


@pytest.mark.parametrize(("text", "problem"), [
    ("mean", "write AGG:COLUMN"), ("mean:", "write AGG:COLUMN"), ("average:time_s", "unknown aggregate 'average'"),
    ("p101:err_cross_arcsec", "must be in [0, 100]"), ("p9.5.1:time_s", "is not a number"),
    ("absrate:correct", "abs does not apply to rate"), ("p95:err cross", "write AGG:COLUMN"), ("", "write AGG:COLUMN"),
])
def test_bad_metrics_are_refused_naming_the_problem(text, problem):
    with pytest.raises(InvalidInputError) as info:
        parse_metric(text)
    assert problem in str(info.value) and repr(text) in str(info.value)


def test_metric_evaluation():
    correct = np.array([True, True, False, True, False])
    cols = {"correct": correct, "solved": np.array([True, True, True, True, False]),
            "err_roll_arcsec": np.array([-3.0, 1.0, 5000.0, 2.0, np.nan]),
            "n_stars": np.array([7, 3, 9, 12, 0], dtype=np.int32), "status": np.array(["OK"] * 5, dtype=object)}
    assert parse_metric("rate:correct").evaluate(cols) == (pytest.approx(0.6), 5)
    assert parse_metric("absmean:err_roll_arcsec").evaluate(cols) == (pytest.approx(2.0), 3)  # correct rows only
    assert parse_metric("max:err_roll_arcsec@solved").evaluate(cols) == (5000.0, 4)
    assert parse_metric("p50:err_roll_arcsec@all").evaluate(cols)[0] == pytest.approx(np.median([-3, 1, 5000, 2]))
    assert parse_metric("min:n_stars").evaluate(cols) == (0.0, 5)
    assert parse_metric("std:n_stars").evaluate(cols)[0] == pytest.approx(np.std([7, 3, 9, 12, 0], ddof=1))
    with pytest.raises(InvalidInputError, match="no trials column 'n_star'"):
        parse_metric("mean:n_star").evaluate(cols)
    with pytest.raises(InvalidInputError, match="rate needs a bool column"):
        parse_metric("rate:n_stars").evaluate(cols)
    with pytest.raises(InvalidInputError, match="not numeric"):
        parse_metric("mean:status").evaluate(cols)
    with pytest.raises(InvalidInputError, match="@n_stars must name a bool column"):
        parse_metric("mean:err_roll_arcsec@n_stars").evaluate(cols)
    assert isinstance(parse_metric("mean:n_stars"), Metric)
