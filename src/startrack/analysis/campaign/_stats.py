"""Statistics of campaign trials: binomial intervals, percentiles, and the ``AGG:COLUMN`` metrics.

- :func:`wilson_interval`: the Wilson score interval of a success rate (Wilson 1927), which keeps
  its coverage near the nominal level for small ``n`` and rates near 0 or 1, where the normal
  ("Wald") interval collapses to a point.
- :func:`rate_upper_bound`: the one-sided upper confidence bound of a rate, for false solves: the
  exact Clopper-Pearson bound ``Beta.ppf(confidence, k + 1, n - k)`` (Clopper & Pearson 1934),
  which for no event seen is ``1 - (1 - confidence)^(1/n)``, the rule of three (``3 / n`` at 95 %,
  Hanley & Lippman-Hand 1983) of large ``n``.
- :func:`percentiles`: NaN-ignoring percentiles (numpy's default linear interpolation).
- :class:`Metric` and :func:`parse_metric`: the mini-language of a spec's ``[[reference]]``
  tables, ``AGG:COLUMN[@ROWS]`` (``docs/campaign_report.md``).

Pure numpy / scipy; no I/O.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import stats

from ...errors import InvalidInputError, require

PERCENTILES: tuple[float, ...] = (50.0, 68.0, 95.0, 99.7)
"""The error percentiles every table and figure reports (the 1-, 2- and 3-sigma levels of a normal
distribution are near 68, 95 and 99.7 %)."""



def _check_confidence(confidence: float) -> float:
    if not 0.0 < confidence < 1.0:
        raise InvalidInputError(f"confidence must be in (0, 1), got {confidence!r}")
    return float(confidence)


def _check_counts(k: int, n: int) -> tuple[int, int]:
    if n < 0 or k < 0 or k > n:
        raise InvalidInputError(f"counts must satisfy 0 <= k <= n, got k = {k}, n = {n}")
    return int(k), int(n)


def wilson_interval(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a binomial rate ``k / n``.

    Parameters
    ----------
    k, n : int
        Successes and trials, ``0 <= k <= n``.
    confidence : float
        Two-sided confidence level in (0, 1).

    Returns
    -------
    (low, high) : tuple of float
        Bounds in [0, 1]; ``(nan, nan)`` when ``n == 0`` (no information).
        With ``z`` the normal quantile of ``(1 + confidence) / 2``:
        ``(k + z^2/2 +- z sqrt(k (n - k) / n + z^2 / 4)) / (n + z^2)``.
    """
    k, n = _check_counts(k, n)
    z = float(stats.norm.ppf(0.5 + _check_confidence(confidence) / 2))
    if n == 0:
        return (math.nan, math.nan)
    centre = (k + z * z / 2) / (n + z * z)
    half = z / (n + z * z) * math.sqrt(k * (n - k) / n + z * z / 4)
    low = 0.0 if k == 0 else max(0.0, centre - half)  # exactly 0 and 1 at the ends, not 1e-17 off
    high = 1.0 if k == n else min(1.0, centre + half)
    return (low, high)


def rate_upper_bound(k: int, n: int, confidence: float = 0.95) -> float:
    """One-sided upper confidence bound of a rate of which ``k`` events were seen in ``n`` trials:
    the exact Clopper-Pearson bound ``scipy.stats.beta.ppf(confidence, k + 1, n - k)``, the rate
    at which seeing ``k`` or fewer has probability ``1 - confidence`` (1 when ``k == n``; NaN when
    ``n == 0``).

    For ``k == 0`` that is ``1 - (1 - confidence)^(1/n)``, whose large-``n`` form is the rule of
    three ``3 / n`` at 95 % (2.996 / n). The rule itself is not used: for small ``n`` it exceeds
    the exact bound (1.0 against 0.63 for n = 3) and even the bound of one event seen (0.87), so
    that seeing a false solve would lower the bound.
    """
    k, n = _check_counts(k, n)
    confidence = _check_confidence(confidence)
    if n == 0:
        return math.nan
    if k == 0:
        return -math.expm1(math.log1p(-confidence) / n)  # 1 - (1 - confidence)^(1/n), accurate for large n
    if k == n:
        return 1.0
    return float(stats.beta.ppf(confidence, k + 1, n - k))


def finite(values: ArrayLike) -> NDArray[np.float64]:
    """The finite values of ``values`` as a flat float64 array."""
    arr = np.asarray(values, dtype=float).ravel()
    return arr[np.isfinite(arr)]


def percentiles(values: ArrayLike, qs: Sequence[float] | NDArray[np.float64] = PERCENTILES) -> NDArray[np.float64]:
    """Percentiles ``qs`` (in [0, 100]) of the finite ``values``; all NaN when there are none.

    Returns
    -------
    ndarray, shape (len(qs),)
        numpy's default (linear) interpolation between order statistics.
    """
    q = np.asarray(qs, dtype=float)
    if np.any((q < 0) | (q > 100)):
        raise InvalidInputError(f"percentiles must be in [0, 100], got {list(qs)}")
    data = finite(values)
    if data.size == 0:
        return np.full(q.shape, np.nan)
    return np.percentile(data, q)


def rms(values: ArrayLike) -> float:
    """Root mean square of the finite ``values`` (NaN when there are none)."""
    data = finite(values)
    return float(np.sqrt(np.mean(data * data))) if data.size else math.nan


def _std(data: NDArray[np.float64]) -> float:
    return float(np.std(data, ddof=1)) if data.size > 1 else math.nan


_REDUCERS: dict[str, Callable[[NDArray[np.float64]], float]] = {
    "mean": np.mean, "median": np.median, "min": np.min, "max": np.max,
    "std": _std, "rms": lambda d: float(np.sqrt(np.mean(d * d))),
}
_METRIC = re.compile(r"^(?P<agg>[a-z]+[0-9.]*):(?P<col>[A-Za-z_][A-Za-z0-9_]*)(?:@(?P<rows>[A-Za-z_][A-Za-z0-9_]*))?$")
AGGREGATES = "mean, median, std, rms, min, max, rate, pNN (e.g. p95, p99.7), and abs + any of these but rate"
ERROR_PREFIX = "err_"
"""Columns taken over the correct trials unless a metric says otherwise (a false solve's error is
that of a wrong identification, degrees, not the accuracy of the tracker)."""


@dataclass(frozen=True)
class Metric:
    """A parsed ``AGG:COLUMN[@ROWS]`` metric (see :func:`parse_metric`).

    Attributes
    ----------
    text : str
        The metric as written.
    agg : str
        "mean", "median", "std", "rms", "min", "max", "rate" or "percentile".
    column : str
        The trials column it reduces.
    q : float or None
        The percentile (0-100) when ``agg == "percentile"``.
    absolute : bool
        Reduce the absolute values.
    rows : str
        "all", or a bool column selecting the rows (default "correct" for ``err_*`` columns,
        else "all").
    """

    text: str
    agg: str
    column: str
    q: float | None = None
    absolute: bool = False
    rows: str = "all"

    def evaluate(self, columns: Mapping[str, ArrayLike]) -> tuple[float, int]:
        """The metric over ``columns`` (name -> 1-D array, e.g. a pyarrow table's columns).

        Returns
        -------
        (value, n_used) : tuple
            The value (NaN when no value enters it) and the number of values that entered.

        Raises
        ------
        InvalidInputError
            If the column or the row selector is missing or of the wrong type.
        """
        data = _column(columns, self.column, self.text)
        if self.rows != "all":
            keep = _column(columns, self.rows, self.text)
            if keep.dtype != np.bool_:
                raise InvalidInputError(f"metric {self.text!r}: @{self.rows} must name a bool column")
            data = data[keep]
        if self.agg == "rate":
            if data.dtype != np.bool_:
                raise InvalidInputError(f"metric {self.text!r}: rate needs a bool column (e.g. rate:correct), "
                                        f"{self.column} is {data.dtype}")
            return (float(data.mean()) if data.size else math.nan, int(data.size))
        if data.dtype.kind not in "biuf":
            raise InvalidInputError(f"metric {self.text!r}: {self.column} is not numeric ({data.dtype})")
        values = finite(np.abs(data) if self.absolute else data)
        if values.size == 0:
            return (math.nan, 0)
        if self.agg == "percentile":
            return (float(np.percentile(values, require(self.q, "the percentile of the metric"))), int(values.size))
        return (float(_REDUCERS[self.agg](values)), int(values.size))


def _column(columns: Mapping[str, ArrayLike], name: str, text: str) -> np.ndarray:
    if name not in columns:
        valid = ", ".join(sorted(columns))
        raise InvalidInputError(f"metric {text!r}: no trials column {name!r}; columns: {valid}")
    col = columns[name]
    return np.asarray(col.to_numpy(zero_copy_only=False) if hasattr(col, "to_numpy") else col)


def _percentile_of(token: str, text: str) -> float:
    try:
        q = float(token)
    except ValueError:
        raise InvalidInputError(f"metric {text!r}: percentile {token!r} is not a number (write e.g. p95)") from None
    if not 0 <= q <= 100:
        raise InvalidInputError(f"metric {text!r}: percentile {q:g} must be in [0, 100]")
    return q


def parse_metric(text: str) -> Metric:
    """Parse ``AGG:COLUMN[@ROWS]``.

    ``AGG`` is one of mean, median, std, rms, min, max, rate (the share of True in a bool column),
    ``pNN`` (the NN-th percentile, e.g. p95, p99.7), or ``abs`` before any of these but rate
    (``absmean``, ``absmedian``, ``abs95`` = ``absp95``: of the absolute values). ``COLUMN`` is a
    trials column. ``ROWS`` selects the rows: ``all`` or a bool column (``solved``, ``correct``);
    without it, ``err_*`` columns are taken over the correct trials and the others over all.
    NaN values never enter.

    Raises
    ------
    InvalidInputError
        Naming what is wrong and what is valid.
    """
    if not isinstance(text, str):
        raise InvalidInputError(f"metric must be a string 'AGG:COLUMN', got {text!r}")
    match = _METRIC.match(text.strip())
    if match is None:
        raise InvalidInputError(f"metric {text!r}: write AGG:COLUMN[@ROWS], e.g. 'p95:err_cross_arcsec' or "
                                f"'rate:correct'; AGG is {AGGREGATES}")
    column = match["col"]
    rows = match["rows"] or ("correct" if column.startswith(ERROR_PREFIX) else "all")
    absolute = match["agg"].startswith("abs")
    agg = match["agg"][3:] if absolute else match["agg"]
    q = None
    if re.fullmatch(r"p?[0-9.]+", agg) and (absolute or agg.startswith("p")):
        q, agg = _percentile_of(agg.lstrip("p"), text), "percentile"
    elif agg == "rate" and absolute:
        raise InvalidInputError(f"metric {text!r}: abs does not apply to rate")
    elif agg != "rate" and agg not in _REDUCERS:
        raise InvalidInputError(f"metric {text!r}: unknown aggregate {match['agg']!r}; valid: {AGGREGATES}")
    return Metric(text=text, agg=agg, column=column, q=q, absolute=absolute, rows=rows)
