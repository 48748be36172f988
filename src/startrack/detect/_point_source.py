"""Point sources told apart from extended and elongated spots (nebula knots, glow, limbs).

Real photographs hold bright spots that are not stars: knots of a nebula, the glow around a
planet or the Moon, a lit limb or an edge. They pass the area and shape filters one by one, yet
patterns built on them never match. A star is the point-spread function (PSF) of the camera,
the same for every star of the frame, so what gives a spot away is its size and shape against
the frame's own stars.

Per spot, the pixels at or above half its peak (background subtracted) are its core: their
number ``A`` gives the half-maximum size ``s = sqrt(A / (2 pi ln 2))`` (the standard deviation
of a Gaussian with that core), independent of the spot's brightness and blind to the wings
(JPEG ringing, halos, a neighbour); their second moments give its elongation (the ratio of
the principal axes, measured on cores of at least :data:`MIN_SHAPE_PIXELS` pixels, else 1).

The frame's reference size is a low quantile of the sizes of its significant spots (the stars
are the narrowest significant things in a frame; knots and glow are wider; unsaturated spots
only, when at least :data:`MIN_REFERENCE_SPOTS` are significant), at least
:data:`MIN_REFERENCE_SIZE_PX` (a core of a few pixels is a point source), its reference
elongation the median elongation (1 for round stars, more when the whole frame is smeared).
The quality is the product of two ramps, each 1 up to the lower end of :data:`SIZE_RAMP` /
:data:`ELONGATION_RAMP` times the reference and 0 from the upper end. Saturated spots (clipped
at the frame's largest value) have a flat core wider than the PSF, so their size does not count;
their core's fill does instead (:data:`FILL_RAMP`): its area over the area of the ellipse of its
second moments (``A / (4 pi sqrt(det C))``: 1 for a filled disc or ellipse, 0.95 for a
rectangle). A clipped star's core is a disc, or a capsule when smeared, and fills it (0.74-0.99
for isolated stars of PSF sd 0.7-2.5 px, peaks 1.5-60 times the clip, smeared 0-8 px, lossless
or JPEG quality 50-95); the strokes of a saturated timestamp, watermark or caption are rings,
hooks and bends that do not (0.21-0.59 on a date rendered 16 and 28 px high on two photos),
and would otherwise pass as the brightest stars of the frame. Thick strokes break into pieces
that do fill their ellipses; the solver's search order (:func:`startrack.solve.spread_rounds`)
keeps those from crowding out the stars. SExtractor's CLASS_STAR and DAOFIND's sharpness and
roundness serve the same end with a neural network and a fitted profile; this is the cheap,
moment-based version.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ._compiled import region_kernels
from ._label import Regions
from ._windows import fast_median, fast_quantile

SIZE_RAMP = (1.6, 2.4)
"""Quality falls from 1 to 0 as the spot's size goes from 1.6 to 2.4 times the frame's."""

ELONGATION_RAMP = (1.7, 2.7)
"""... and as its elongation goes from 1.7 to 2.7 times the frame's."""

FILL_RAMP = (0.75, 0.6)
"""A saturated spot's quality is 1 down to a core fill of 0.75 and 0 from 0.6 (module docstring)."""

REFERENCE_QUANTILE = 0.3
"""The frame's star size: this quantile of the significant spots' sizes."""

MIN_REFERENCE_SNR = 10.0
"""Spots with a peak SNR at least this make the reference (all spots when fewer than
:data:`MIN_REFERENCE_SPOTS` do)."""

MIN_REFERENCE_SPOTS = 5
MIN_REFERENCE_SIZE_PX = 0.75
"""The reference size is at least this: a core of a few pixels is as small as a sampled star
can be, whatever the frame's smallest spots (noise, hot pixels) measure."""
MIN_SHAPE_PIXELS = 6
HALF_MAX_AREA = 2.0 * np.pi * np.log(2.0)
"""Area above half maximum of a Gaussian of unit standard deviation, px^2."""


class CoreShape(NamedTuple):
    """The half-maximum core of N spots (module docstring), each of shape (N,)."""

    size: NDArray[np.float64]
    """Gaussian-equivalent standard deviation of the core's area (px)."""
    elongation: NDArray[np.float64]
    """Ratio of the core's principal axes (>= 1; 1 for cores under :data:`MIN_SHAPE_PIXELS`)."""
    fill: NDArray[np.float64]
    """Core area over the area of its second moments' ellipse (1 for cores under
    :data:`MIN_SHAPE_PIXELS`)."""


def core_shape(regions: Regions, signal: NDArray, peak: NDArray) -> CoreShape:
    """Half-maximum size (px), elongation (>= 1) and fill of N spots (module docstring), one
    compiled loop over the pixels (:func:`.region_kernels.core_shapes`).

    Parameters
    ----------
    regions : Regions
        The spots' full-resolution pixels.
    signal : ndarray, shape (M,)
        Background-subtracted value of each region pixel (NaN or 0 where missing).
    peak : ndarray, shape (N,)
        Each spot's largest signal.
    """
    shape = region_kernels().core_shapes(regions.starts, np.asarray(regions.x, np.int64),
                                         np.asarray(regions.y, np.int64), np.ascontiguousarray(signal, np.float64),
                                         np.ascontiguousarray(peak, np.float64), MIN_SHAPE_PIXELS, HALF_MAX_AREA)
    return CoreShape(shape[0], shape[1], shape[2])


def saturated_spots(regions: Regions, raw: NDArray, top: float) -> NDArray[np.bool_]:
    """Spots with at least two pixels at the frame's largest value (clipped cores), shape (N,).

    Parameters
    ----------
    regions : Regions
    raw : ndarray, shape (M,)
        Value of every region pixel in the frame (NaN where missing).
    top : float
        The frame's largest value (:func:`frame_top`).
    """
    with np.errstate(invalid="ignore"):
        return regions.sum((raw >= top).astype(np.float64)) >= 2


def frame_top(data: NDArray) -> float:
    """The largest value of the frame ``data`` (H, W), NaN left out (inf when empty)."""
    if not data.size:
        return np.inf
    return float(data.max() if data.dtype.kind in "biu" else np.nanmax(data))


def point_quality(shape: CoreShape, peak_snr: NDArray, saturated: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Point-source quality in [0, 1] of N spots from their cores' sizes, elongations and, for
    the ``saturated`` ones (shape (N,)), fills instead of sizes (module docstring); a spot
    without a finite measurement counts as a point source (1)."""
    ref_size, ref_elongation = _references(shape.size, shape.elongation, peak_snr, saturated)
    q_size = _ramp(shape.size / ref_size, *SIZE_RAMP)
    if saturated.any():
        q_size = np.where(saturated, _ramp(shape.fill, *FILL_RAMP), q_size)
    quality = q_size * _ramp(shape.elongation / ref_elongation, *ELONGATION_RAMP)
    return np.where(np.isfinite(quality), quality, 1.0)


def _references(size: NDArray, elongation: NDArray, peak_snr: NDArray, saturated: NDArray[np.bool_]
                ) -> tuple[float, float]:
    """The frame's star size and elongation from its significant, measurable spots, unsaturated
    ones when there are enough (a clipped core is wider than the PSF, and the pieces of a
    saturated caption can outnumber the stars)."""
    ok = np.isfinite(size) & np.isfinite(elongation) & (size > 0)
    strong = ok & (peak_snr >= MIN_REFERENCE_SNR)  # NaN is not
    unsaturated = strong & ~saturated if saturated.any() else strong
    use = next((s for s in (unsaturated, strong) if np.count_nonzero(s) >= MIN_REFERENCE_SPOTS), ok)
    if not use.any():
        return 1.0, 1.0
    ref_size = fast_quantile(size[use], REFERENCE_QUANTILE)  # np.quantile's and np.median's values
    return max(ref_size, MIN_REFERENCE_SIZE_PX), max(float(fast_median(elongation[use])), 1.0)


def _ramp(ratio: NDArray, start: float, stop: float) -> NDArray[np.float64]:
    """1 up to ``start``, 0 from ``stop``, linear between (NaN stays NaN); with ``stop`` below
    ``start``, 1 down to ``start`` and 0 from ``stop``."""
    with np.errstate(invalid="ignore"):
        return np.clip((stop - ratio) / (stop - start), 0.0, 1.0)
