"""Analysis 3: the residual of each matched star against its distance from the principal point,
with a second-order fit (Fowler 2013 Ch. 9 §VIII.C: an even-order trend means radial
distortion is left in the lens model).

The fit is ordinary least squares of ``residual = c0 + c1 r + c2 r^2`` per result set (r in px,
residual in arcsec), with the coefficients' 1-sigma uncertainties from the residual variance,
``s^2 (A^T A)^-1`` with ``s^2 = RSS / (N - 3)``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ._core import AnalysisInfo, AnalysisResult, ResultSet
from ._figures import colour, draw_radial_fit, new_figure, no_data
from ._spots import star_table

INFO = AnalysisInfo(
    name="radial",
    title="Residual against radius, with a second-order fit",
    description="Angle between each matched star and its catalog star after the fit, against the "
                "distance of the spot from the principal point (the image centre for an uncalibrated "
                "camera), with the least-squares fit c0 + c1 r + c2 r^2 per result set. A significant c2 "
                "means radial distortion is left. Fowler 2013 Ch. 9 §VIII.C.",
    min_sets=1, max_sets=6,
)
COEFFICIENTS = (("c0", "arcsec"), ("c1", "arcsec/px"), ("c2", "arcsec/px^2"))


def quadratic_fit(radius: NDArray, value: NDArray) -> tuple[NDArray, NDArray]:
    """Least-squares ``c0 + c1 r + c2 r^2`` and the 1-sigma uncertainty of each (lowest power
    first); NaN when fewer than four points (no degree of freedom left for the variance)."""
    r, v = np.asarray(radius, float), np.asarray(value, float)
    if r.size < 4:
        return np.full(3, np.nan), np.full(3, np.nan)
    design = np.stack([np.ones_like(r), r, r * r], axis=1)
    coef, *_ = np.linalg.lstsq(design, v, rcond=None)
    rss = float(np.sum((v - design @ coef) ** 2))
    cov = rss / (r.size - 3) * np.linalg.inv(design.T @ design)
    return coef, np.sqrt(np.diag(cov))


def run(sets: Sequence[ResultSet], params: dict) -> AnalysisResult:
    """The analysis of this module over result sets and parameters already checked by
    :func:`~.registry.run_analysis` (see :data:`INFO` and the module docstring)."""
    stars = star_table(sets)
    fig, axes = new_figure(1, 1, width_in=7.0, height_in=4.5, title=INFO.title)
    ax = axes[0, 0]
    fit: dict[str, list] = {k: [] for k in ("set", "coefficient", "value", "sigma", "unit", "n_stars")}
    summary: dict[str, float | int | str] = {}
    for i, s in enumerate(sets):
        mask = stars["set"] == s.name
        r, res = stars["radius_px"][mask], stars["residual_arcsec"][mask]
        coef, sigma = quadratic_fit(r, res)
        draw_radial_fit(ax, r, res, None if np.isnan(coef[0]) else coef[::-1], colour_name=colour(i),
                        label=f"{s.name}: c2 = {coef[2]:.3g} +- {sigma[2]:.2g} arcsec/px^2")
        for (name, unit), c, e in zip(COEFFICIENTS, coef, sigma, strict=True):
            for key, value in zip(fit, (s.name, name, float(c), float(e), unit, int(r.size)), strict=True):
                fit[key].append(value)
        summary[f"{s.name}: stars"] = int(r.size)
        summary[f"{s.name}: rms residual, arcsec"] = float(np.sqrt(np.mean(res**2))) if r.size else float("nan")
        summary[f"{s.name}: c2, arcsec/px^2"] = float(coef[2])
        summary[f"{s.name}: c2 / sigma"] = float(coef[2] / sigma[2]) if sigma[2] > 0 else float("nan")
    if stars["radius_px"].size == 0:
        no_data(ax, "no matched stars")
    else:
        ax.set_xlabel("distance from the principal point, px")
        ax.set_ylabel("residual, arcsec")
        ax.legend(fontsize=8)
    columns = ("set", "record", "index", "hip", "x", "y", "radius_px", "residual_arcsec")
    return AnalysisResult(INFO.name, INFO.title, fig, {"stars": {k: stars[k] for k in columns}, "fit": fit}, summary)
