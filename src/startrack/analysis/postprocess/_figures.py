"""Figure helpers of the analyses: matplotlib's object API only (``matplotlib.figure.Figure``; no
pyplot, no backend switch), so that a server can build figures in any thread.

Axis-level drawings that more than one analysis uses live here: the residual-against-radius
scatter with its second-order fit and the fixed-mount errors over time (the pictures of
:mod:`startrack.analysis._calibration_plots`, drawn on a given axis).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ... import plotting
from ...calibrate import Repeatability
from ...units import ARCMIN

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")
"""One colour per result set (the analyses take at most six)."""
DPI = 100


def new_figure(rows: int, cols: int, *, width_in: float = 4.2, height_in: float = 3.4,
               title: str = "") -> tuple[Figure, NDArray]:
    """A figure of ``rows x cols`` axes (a 2-D array of them), laid out with constrained layout."""
    fig = plotting.new_figure(figsize=(width_in * cols, height_in * rows + (0.4 if title else 0.0)), dpi=DPI,
                              layout="constrained")
    axes = np.atleast_2d(fig.subplots(rows, cols, squeeze=False))
    if title:
        fig.suptitle(title, fontsize=11)
    return fig, axes


def colour(i: int) -> str:
    """The colour of the i-th result set."""
    return COLOURS[i % len(COLOURS)]


def no_data(ax: Axes, text: str = "no data") -> None:
    """Mark an axis that has nothing to show."""
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", color="0.4")
    ax.set_xticks([])
    ax.set_yticks([])


def draw_radial_fit(ax: Axes, radius: NDArray, value: NDArray, coef: Sequence[float] | NDArray | None, *,
                    colour_name: str = "tab:blue", label: str = "") -> None:
    """Scatter of ``value`` against ``radius`` and the polynomial ``coef`` (highest power first,
    as :func:`numpy.polyval` takes it) over 0..max radius (Fowler 2013 §VIII.C)."""
    ax.scatter(radius, value, s=6, color=colour_name, alpha=0.6, label=label or None)
    if coef is not None and radius.size:
        r = np.linspace(0.0, float(np.max(radius)), 100)
        ax.plot(r, np.polyval(coef, r), color=colour_name, linewidth=1.5)


def draw_repeatability(ax: Axes, result: Repeatability) -> None:
    """Total, pointing and roll error of each image against the mean mount (arcmin) over time."""
    minutes = (result.times - result.times[0]).to_value("min")
    for name, values in (("total", result.total_rad), ("pointing", result.pointing_rad),
                         ("roll", result.roll_rad)):
        ax.plot(minutes, values / ARCMIN, marker=".", label=name)
    ax.set_xlabel("minutes from the first image")
    ax.set_ylabel("error against the mean mount, arcmin")
    ax.legend(fontsize=8)


def shared_bins(values: Sequence[NDArray], bins: int, *, log: bool = False, integer: bool = False) -> NDArray:
    """Bin edges common to several samples: ``bins`` equal bins over their joint range (in
    log10 when ``log``; at whole numbers when ``integer`` and the range allows one per value)."""
    finite = [v[np.isfinite(v) & ((v > 0) if log else True)] for v in values]
    joined = np.concatenate(finite) if finite else np.zeros(0)
    if joined.size == 0:
        return np.linspace(0.0, 1.0, bins + 1)
    lo, hi = float(joined.min()), float(joined.max())
    if log:
        lo, hi = np.log10(lo), np.log10(hi)
    if hi <= lo:
        hi = lo + 1.0
    if integer and not log and hi - lo + 1 <= bins:
        return np.arange(np.floor(lo), np.floor(hi) + 2) - 0.5
    edges = np.linspace(lo, hi, bins + 1)
    if log:  # 10**log10(v) may round below v: put the outer edges on the extreme values themselves
        edges = 10.0**edges
        edges[0], edges[-1] = joined.min(), max(joined.max(), edges[-1])
    return edges
