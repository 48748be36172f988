"""Instrument magnitudes of detected stars, and their calibration against a catalogue.

Huffman 2006 §5.3 inverts its signal model, eq. 3.4, to get a visual
magnitude from the measured electrons; Jacobs 1995 (§2.2.4, App C.1) does the same
with an illuminance constant ``k_illum`` calibrated by matching imaged stars to the catalogue.
Both are, in magnitudes, one zero point::

    m_inst = zero_point - 2.5 log10(flux)

``flux`` in the image's units (ADU, background subtracted) and ``zero_point`` the magnitude of a
star of flux 1. :func:`calibrate_zero_point` finds it from detections matched to catalogue stars
(the Jacobs 1995 procedure, with a median instead of a mean so that a mismatched star or a saturated
one does not pull it). Jacobs 1995's ``brightness = sum b_i + k_area n delta_th`` adds back the
threshold its region pixels had subtracted; our flux is measured above the background, not above
the threshold, so :func:`jacobs1995_brightness` is only needed to reproduce that thesis.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError, as_float_array, checked_number

MAG_PER_DEX = 2.5
JACOBS1995_K_AREA = 2.0
"""Jacobs 1995's empirical area factor k_area (Jacobs 1995 §2.2.4, App C.1)."""


def instrument_magnitude(flux: ArrayLike, zero_point: float = 0.0) -> NDArray[np.float64]:
    """``zero_point - 2.5 log10(flux)``; NaN where the flux is not positive."""
    f = as_float_array(flux, "flux")
    zero_point = checked_number(zero_point, "zero_point (mag)")
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(f > 0, zero_point - MAG_PER_DEX * np.log10(f), np.nan)


def calibrate_zero_point(flux: ArrayLike, catalog_mag: ArrayLike) -> tuple[float, float]:
    """Zero point that makes :func:`instrument_magnitude` equal the catalogue magnitudes.

    Parameters
    ----------
    flux : array_like, shape (K,)
        Measured fluxes of K detections matched to catalogue stars.
    catalog_mag : array_like, shape (K,)
        Their catalogue magnitudes (e.g. Hipparcos V).

    Returns
    -------
    zero_point, scatter_mag : float
        The median of ``catalog_mag + 2.5 log10(flux)`` and the robust scatter (1.4826 MAD) of
        the individual values, in magnitudes.

    Raises
    ------
    InvalidInputError
        Shapes differ, or no pair has a positive flux and a finite magnitude.
    """
    f, m = as_float_array(flux, "flux"), as_float_array(catalog_mag, "catalog_mag")
    if f.shape != m.shape or f.ndim != 1:
        raise InvalidInputError(
            f"flux and catalog_mag must be 1-D arrays of one length, got {f.shape} and {m.shape}")
    use = (f > 0) & np.isfinite(f) & np.isfinite(m)
    if not use.any():
        raise InvalidInputError("calibrate_zero_point needs at least one positive flux with a "
                                "finite catalogue magnitude")
    values = m[use] + MAG_PER_DEX * np.log10(f[use])
    zero_point = float(np.median(values))
    return zero_point, float(1.4826 * np.median(np.abs(values - zero_point)))


def jacobs1995_brightness(flux_above_threshold: ArrayLike, area_px: ArrayLike, delta_threshold: float,
                       k_area: float = JACOBS1995_K_AREA) -> NDArray[np.float64]:
    """Jacobs 1995 eq. (§2.2.4): ``sum b_i + k_area * n * delta_th``, the region's summed values
    above the threshold plus the threshold's share, with its empirical ``k_area = 2``."""
    return (np.asarray(flux_above_threshold, dtype=np.float64)
            + k_area * np.asarray(area_px, dtype=np.float64) * delta_threshold)
