"""The ECSS-E-ST-60-20C terms of an error budget's cells, and each source's contribution.

A budget's cells (:mod:`._budget`) share their star fields; trial k of a cell is frame k mod R of
dither (k // R) mod D of star field k // (R D) (R repeats, D dithers in the manifest's ``budget``).
:func:`ecss_terms` splits a cell's signed errors (camera x, y, roll) into the bias (the mean),
the FOV spatial error (between star fields), the pixel spatial error (between sub-pixel dithers of
one field) and the temporal noise (between repeated frames of one attitude), by the method of
moments of a nested random-effects model; :func:`budget_rows` sets each source's cell against the
baseline. ``docs/error_budget.md`` says why these estimate the ECSS terms.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

TERMS = ("bias", "fov_spatial", "pixel_spatial", "temporal", "total")
"""The terms of a cell's error (docs/error_budget.md): the bias (mean signed error over the cell),
the FOV spatial error (the spread of the error between star fields: what depends on where the stars
fall in the field and on the sky), the pixel spatial error (between sub-pixel dithers of one field)
and the temporal noise (between repeated frames of one attitude); ``total`` is the RMS error."""
AXES = ("cross", "roll")


@dataclass(frozen=True)
class EcssTerms:
    """The terms of one cell, per axis (camera x, y, roll).

    Attributes
    ----------
    bias : ndarray, shape (3,)
        Mean signed error (arcsec).
    fov_spatial, pixel_spatial, temporal : ndarray, shape (3,)
        Variance estimates (arcsec^2; an estimate may come out below zero by chance; NaN when the
        design cannot separate the term: one repeat, one dither or one field).
    mean_square : ndarray, shape (3,)
        Mean square error (arcsec^2).
    n : int
        Trials used.
    bias_var : ndarray, shape (3,)
        Variance of the bias estimate (arcsec^2): that of the star fields' mean errors over the
        number of fields (NaN with one field).
    """

    bias: np.ndarray
    fov_spatial: np.ndarray
    pixel_spatial: np.ndarray
    temporal: np.ndarray
    mean_square: np.ndarray
    n: int
    bias_var: np.ndarray = dataclasses.field(default_factory=lambda: np.full(3, math.nan))

    def power(self, term: str, axis: str) -> float:
        """The squared size (arcsec^2) of ``term`` on ``axis``: "cross" adds x and y, "roll" is z."""
        values = {"bias": self.bias**2, "fov_spatial": self.fov_spatial, "pixel_spatial": self.pixel_spatial,
                  "temporal": self.temporal, "total": self.mean_square}[term]
        return float(values[0] + values[1]) if axis == "cross" else float(values[2])

    def size(self, term: str, axis: str) -> float:
        """The term's size (arcsec): the square root of :meth:`power` (0 for a negative estimate)."""
        power = self.power(term, axis)
        return math.sqrt(max(power, 0.0)) if math.isfinite(power) else math.nan


def _group_means(e: np.ndarray, group: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unique groups, their sizes and means."""
    keys, inverse, counts = np.unique(group, return_inverse=True, return_counts=True)
    return keys, counts, np.bincount(inverse, weights=e) / counts


def variance_components(e: np.ndarray, field: np.ndarray, dither: np.ndarray) -> tuple[float, float, float]:
    """(FOV spatial, pixel spatial, temporal) variances of errors ``e`` (M,) in a nested design.

    Frames are grouped by attitude (``field``, ``dither``) and attitudes by ``field``. The
    method-of-moments estimates of a nested random-effects model: temporal = the pooled variance
    within attitudes; pixel = the pooled variance of attitude means within fields less temporal x
    mean(1/n); FOV = the variance of field means less the part the two others put there. Exact
    (unbiased) for a balanced design, nearly so when failed trials leave holes.
    """
    att = field.astype(np.int64) * (int(dither.max(initial=0)) + 1) + dither
    keys, n_att, m_att = _group_means(e, att)
    inverse = np.searchsorted(keys, att)
    df_t = float(np.sum(n_att - 1))
    temporal = float(np.sum((e - m_att[inverse]) ** 2) / df_t) if df_t > 0 else math.nan
    t_used = 0.0 if math.isnan(temporal) else temporal
    att_field = keys // (int(dither.max(initial=0)) + 1)
    fields, d_f, m_f = _group_means(m_att, att_field)
    inv_f = np.searchsorted(fields, att_field)
    inv_n = np.bincount(inv_f, weights=1.0 / n_att) / d_f  # mean of 1/n over each field's attitudes
    multi = d_f > 1
    if np.any(multi):
        ss = np.bincount(inv_f, weights=(m_att - m_f[inv_f]) ** 2)
        pixel = float(np.sum((ss - (d_f - 1) * t_used * inv_n)[multi]) / np.sum(d_f[multi] - 1))
    else:
        pixel = math.nan
    if fields.size < 2:
        return math.nan, pixel, temporal
    p_used = 0.0 if math.isnan(pixel) else pixel
    fov = float(np.var(m_f, ddof=1) - p_used * np.mean(1.0 / d_f) - t_used * np.mean(inv_n / d_f))
    return fov, pixel, temporal


def _bias_var(err: np.ndarray, fields: np.ndarray) -> np.ndarray:
    """Variance (3,) of the mean error: that of the fields' means over the number of fields."""
    keys = np.unique(fields)
    if keys.size < 2:
        return np.full(3, math.nan)
    means = np.array([err[fields == k].mean(axis=0) for k in keys])
    return means.var(axis=0, ddof=1) / keys.size


def ecss_terms(err_arcsec: np.ndarray, fields: np.ndarray, dither: np.ndarray) -> EcssTerms:
    """The terms of a cell from its trials' signed errors ``err_arcsec`` (M, 3) (camera x, y, roll)
    with their star field and dither indices (M,) (see :func:`variance_components`)."""
    err = np.asarray(err_arcsec, dtype=float).reshape(-1, 3)
    if not len(err):
        nan = np.full(3, math.nan)
        return EcssTerms(nan, nan, nan, nan, nan, 0)
    parts = np.array([variance_components(err[:, a], fields, dither) for a in range(3)])
    return EcssTerms(bias=err.mean(axis=0), fov_spatial=parts[:, 0], pixel_spatial=parts[:, 1], temporal=parts[:, 2],
                     mean_square=(err**2).mean(axis=0), n=len(err), bias_var=_bias_var(err, fields))


def _bias_size(bias: np.ndarray, axis: str) -> float:
    return float(math.hypot(bias[0], bias[1])) if axis == "cross" else float(abs(bias[2]))


def contribution(cell: EcssTerms, baseline: EcssTerms, term: str, axis: str) -> float:
    """A source's contribution (arcsec) to ``term`` on ``axis``.

    The bias: the size of the shift of the mean error vector (the cells share their attitudes, so
    biases add as vectors). Every other term: the root-sum-square difference
    sqrt(P_cell - P_baseline) of its powers (:meth:`EcssTerms.power`), negative
    (-sqrt(P_baseline - P_cell)) when the cell came out below the baseline.
    """
    if term == "bias":
        return _bias_size(cell.bias - baseline.bias, axis)
    diff = cell.power(term, axis) - baseline.power(term, axis)
    return math.copysign(math.sqrt(abs(diff)), diff) if math.isfinite(diff) else math.nan


def cell_terms(trials: Mapping[str, np.ndarray], cell: int, design: Mapping[str, Any]) -> EcssTerms:
    """The terms of manifest cell ``cell`` over its correct trials (columns as numpy arrays)."""
    rows = (trials["cell"] == cell) & trials["correct"].astype(bool)
    k = trials["trial"][rows].astype(np.int64)
    repeats, dithers = int(design["repeats"]), int(design["dithers"])
    err = np.column_stack([trials[f"err_{a}_arcsec"][rows] for a in ("x", "y", "roll")])
    return ecss_terms(err, k // (repeats * dithers), (k // repeats) % dithers)


def budget_rows(trials: Mapping[str, np.ndarray], budget: Mapping[str, Any]) -> list[dict[str, Any]]:
    """Per case: one row per cell (baseline, all, each source) with each term's size
    (``<axis>_<term>_arcsec``) and its contribution against the baseline
    (``contrib_<axis>_<term>_arcsec``, :func:`contribution`), for axis in :data:`AXES` and term in
    :data:`TERMS`, and the bias's standard error ``<axis>_bias_se_arcsec``; then a row ``sum``:
    the single sources combined (their bias shifts as vectors, every other term in quadrature),
    with all-on's contribution over that in ``ratio_<axis>_<term>`` (1: the sources add up so)."""
    out = []
    for case in budget["cases"]:
        cells = {"baseline": case["baseline"], "all": case["all"], **case["sources"]}
        terms = {name: cell_terms(trials, index, budget) for name, index in cells.items()}
        rows = [_cell_row(case["name"], name, index, terms[name], terms["baseline"], trials)
                for name, index in cells.items()]
        out += [*rows, _sum_row(case["name"], rows, terms)]
    return out


def _cell_row(case: str, source: str, cell: int, terms: EcssTerms, base: EcssTerms,
              trials: Mapping[str, np.ndarray]) -> dict[str, Any]:
    row = {"case": case, "source": source, "cell": cell, "n_used": terms.n,
           "n_trials": int(np.sum(trials["cell"] == cell))}
    for axis in AXES:
        for term in TERMS:
            row[f"{axis}_{term}_arcsec"] = terms.size(term, axis)
            row[f"contrib_{axis}_{term}_arcsec"] = contribution(terms, base, term, axis)
            row[f"ratio_{axis}_{term}"] = math.nan
        var = terms.bias_var
        row[f"{axis}_bias_se_arcsec"] = math.sqrt(var[0] + var[1] if axis == "cross" else var[2])
    return row


def _sum_row(case: str, rows: list[dict[str, Any]], terms: Mapping[str, EcssTerms]) -> dict[str, Any]:
    singles = [r for r in rows if r["source"] not in ("baseline", "all")]
    every = next(r for r in rows if r["source"] == "all")
    shift = sum((terms[r["source"]].bias - terms["baseline"].bias for r in singles), np.zeros(3))
    row = {"case": case, "source": "sum", "cell": -1, "n_used": 0, "n_trials": 0,
           **{f"{axis}_bias_se_arcsec": math.nan for axis in AXES}}
    for axis in AXES:
        for term in TERMS:
            key = f"contrib_{axis}_{term}_arcsec"
            if term == "bias":
                combined = _bias_size(shift, axis)
            else:
                power = sum(math.copysign(r[key] ** 2, r[key]) for r in singles if math.isfinite(r[key]))
                combined = math.copysign(math.sqrt(abs(power)), power)
            row.update({f"{axis}_{term}_arcsec": math.nan, key: combined,
                        f"ratio_{axis}_{term}": every[key] / combined if combined > 0 else math.nan})
    return row
