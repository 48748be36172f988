"""The full per-detection record: :class:`startrack.results.Detections` plus what only the
detection stage knows (instrument magnitude, shape, the threshold used)."""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np
from numpy.typing import NDArray

from ..results import Detections

PER_DETECTION = ("mag", "peak_snr", "major_px", "minor_px", "angle_deg", "psf_sigma_px")


def _empty() -> NDArray[np.float64]:
    return np.zeros(0)


@dataclass(frozen=True)
class DetectionDetails:
    """Detections and their extra measurements, aligned (brightest first).

    Attributes
    ----------
    detections : Detections
    mag : ndarray, shape (N,)
        Instrument magnitude ``mag_zero_point - 2.5 log10(flux)`` (:mod:`._magnitude`).
    peak_snr : ndarray, shape (N,)
        Peak pixel over the local pixel noise (Huffman 2006 eq. 3.18).
    major_px, minor_px, angle_deg : ndarray, shape (N,)
        Jacobs 1995's long and short axis and the long axis's direction from +x towards +y
        (:mod:`._shape`).
    psf_sigma_px : ndarray, shape (N,)
        PSF width fitted (``centroid="mle"``) or used by the centroider, else the spot's
        intensity-weighted RMS radius.
    k_sigma : float
        Detection threshold used, in noise units (chosen by the dynamic threshold, else the
        setting).
    centroid : str
        Name of the centroider.
    """

    detections: Detections = field(default_factory=Detections)
    mag: NDArray[np.float64] = field(default_factory=_empty)
    peak_snr: NDArray[np.float64] = field(default_factory=_empty)
    major_px: NDArray[np.float64] = field(default_factory=_empty)
    minor_px: NDArray[np.float64] = field(default_factory=_empty)
    angle_deg: NDArray[np.float64] = field(default_factory=_empty)
    psf_sigma_px: NDArray[np.float64] = field(default_factory=_empty)
    k_sigma: float = float("nan")
    centroid: str = ""

    def __len__(self) -> int:
        return len(self.detections)

    def take(self, index) -> DetectionDetails:
        """A subset or reordering, by index array or boolean mask."""
        extra = {name: getattr(self, name)[index] for name in PER_DETECTION}
        return DetectionDetails(detections=self.detections.take(index), **extra,
                                k_sigma=self.k_sigma, centroid=self.centroid)

    def as_records(self) -> list[dict]:
        """One dict per detection with every per-detection field (for JSON output)."""
        det = self.detections
        columns = {f.name: getattr(det, f.name) for f in fields(det)
                   if isinstance(getattr(det, f.name), np.ndarray)}
        columns.update({name: getattr(self, name) for name in PER_DETECTION})
        return [{k: _plain(v[i]) for k, v in columns.items()} for i in range(len(det))]


def _plain(value) -> float | int | None:
    """A numpy scalar as a JSON-ready Python number (None for NaN)."""
    if isinstance(value, np.integer):
        return int(value)
    value = float(value)
    return value if np.isfinite(value) else None
