"""The configured star detector: background -> threshold -> label -> filter -> centroid.

See the package docstring of :mod:`startrack.detect` for the pipeline and its defaults.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..io.channels import channel_index
from ..results import Detections
from . import filters
from .background import (
    BackgroundModel,
    global_background,
    pixel_noise,
    tiled_background,
    with_noise_floor,
)
from .centroid import (
    UNCERTAINTY_MODELS,
    SpotMeasurements,
    centroid_sigma,
    measure_spots,
    take_spots,
)
from .deblend import split_regions
from .label import Regions, hysteresis_regions
from .prepare import PreparedImage, prepare_image
from .smooth import KERNELS, detection_image
from .threshold import significance

BACKGROUND_MODES = ("tiled", "global")
NOISE_FLOOR_FRACTION = 1e-6
"""Noise floor relative to the largest absolute value, for noise-free (simulated) images."""


@dataclass(frozen=True)
class StarDetector:
    """Star detector with fixed settings (validated once, when constructed).

    Parameters
    ----------
    sigma : float
        Detection threshold k, in noise units of the detection image (binned and smoothed).
    grow_sigma : float
        Lower threshold to which a detected spot is grown (hysteresis); equal to ``sigma``
        for a single threshold.
    binning : int
        Block size of the mean binning of the detection image (1 = none).
    kernel : {"binomial", "box"}
        Smoothing kernel applied after binning (see :mod:`.smooth`).
    kernel_px : int
        Odd size of that kernel in binned pixels (1 = no smoothing).
    background : {"tiled", "global"}
        Tiled: median and noise per ``tile_px`` tile, interpolated (for gradients, trees,
        moonlight). Global: one level and noise for the whole frame.
    tile_px : int
        Tile side in full-resolution pixels.
    min_area_px, max_area_px : int, int or None
        Limits on the spot's pixel count at full resolution (a binned pixel counts
        ``binning**2``).
    min_peak_snr : float
        Minimum peak pixel / pixel noise.
    max_elongation : float or None
        Maximum ratio of the principal axes of the spot.
    min_flatness : float
        Minimum std / peak of the spot's values (seed 003 flatness factor / 100).
    max_peak_fraction : float or None
        Hot-pixel rejection: maximum peak / sum of the 3 x 3 pixels around it.
    max_clutter : float or None
        Clutter rejection: drop spots where the local lower-half noise of the background
        exceeds this multiple of the clean sky's (lit trees, roofs); tiled background only.
    deblend : bool
        Split clusters that hold several separate peaks (see :mod:`.deblend`).
    reject_edge : bool
        Drop spots that touch the image border.
    channel : {None, "r", "g", "b", 0, 1, 2}
        Plane of a colour image to use; None sums R + G + B (see :mod:`startrack.io.channels`).
    max_stars : int or None
        Keep only this many spots, the brightest.
    uncertainty : {"propagated", "eq4.2"}
        Model of ``Detections.sigma_px`` (see :mod:`.centroid`).
    """

    sigma: float = 5.0
    grow_sigma: float = 3.0
    binning: int = 2
    kernel: str = "binomial"
    kernel_px: int = 3
    background: str = "tiled"
    tile_px: int = 32
    min_area_px: int = 4
    max_area_px: int | None = 4096
    min_peak_snr: float = 0.0
    max_elongation: float | None = 5.0
    min_flatness: float = 0.0
    max_peak_fraction: float | None = 0.75
    max_clutter: float | None = 2.5
    deblend: bool = True
    reject_edge: bool = True
    channel: str | int | None = None
    max_stars: int | None = None
    uncertainty: str = "propagated"

    def __post_init__(self) -> None:
        _check_positive(self, ("sigma", "grow_sigma"))
        _check_int(self, ("binning", "kernel_px", "tile_px", "min_area_px"), minimum=1)
        _check_int(self, ("max_area_px", "max_stars"), minimum=1, optional=True)
        _check_positive(self, ("max_elongation", "max_peak_fraction", "max_clutter"),
                        optional=True)
        _check_non_negative(self, ("min_peak_snr", "min_flatness"))
        if self.kernel_px % 2 == 0:
            raise InvalidInputError(
                f"kernel_px must be an odd integer (1, 3, 5...), got {self.kernel_px}")
        if self.kernel not in KERNELS:
            raise InvalidInputError(f"kernel must be one of {KERNELS}, got {self.kernel!r}")
        if self.background not in BACKGROUND_MODES:
            raise InvalidInputError(
                f"background must be one of {BACKGROUND_MODES}, got {self.background!r}")
        if self.uncertainty not in UNCERTAINTY_MODELS:
            raise InvalidInputError(
                f"uncertainty must be one of {UNCERTAINTY_MODELS}, got {self.uncertainty!r}")
        channel_index(self.channel)
        for name in ("reject_edge", "deblend"):
            if not isinstance(getattr(self, name), bool | np.bool_):
                raise InvalidInputError(
                    f"{name} must be True or False, got {getattr(self, name)!r}")

    def settings(self) -> dict:
        """The settings as a plain dict (for logs and result files)."""
        return asdict(self)

    def detect(self, image: NDArray) -> Detections:
        """Find and centroid the stars of ``image``.

        Parameters
        ----------
        image : array_like, shape (H, W) or (H, W, C)
            Raw counts, any integer or float dtype; NaN / inf pixels are ignored.

        Returns
        -------
        Detections
            Brightest (largest flux) first; empty for a blank or constant frame.

        Raises
        ------
        InvalidInputError
            Bad shape, dtype or size, or no finite pixel.
        """
        prepared = prepare_image(image, self.channel)
        binning = min(self.binning, *prepared.data.shape)
        det = detection_image(prepared.data, binning, self.kernel, self.kernel_px,
                              prepared.invalid)
        model = self._background_model(det, binning)
        noise_px = pixel_noise(prepared.data, model) or _floor(prepared.data, model.level)
        empty = Detections(background=model.level, noise=noise_px, width=prepared.data.shape[1],
                           height=prepared.data.shape[0])
        if model.noise <= 0:  # a constant image
            return empty
        regions = self._find_regions(det, significance(det, model, binning))
        if len(regions) == 0:
            return empty
        spots, local_noise = self._measure(prepared, regions.upsample(binning), model, noise_px)
        return self._to_detections(spots, local_noise, empty)

    def _find_regions(self, det: NDArray, snr: NDArray) -> Regions:
        """Threshold, label, deblend and edge-filter on the detection image's grid."""
        regions = hysteresis_regions(snr, self.sigma, self.grow_sigma)
        if self.deblend and len(regions):
            regions = split_regions(regions, snr, self.sigma)
        if self.reject_edge and len(regions):
            core = snr[regions.y, regions.x] > self.sigma
            regions = regions.select(filters.away_from_edge(regions, det.shape, core))
        return regions

    def _background_model(self, det: NDArray, binning: int) -> BackgroundModel:
        """Background of the detection image, tile centres in full-resolution pixels."""
        if self.background == "global":
            model = global_background(det)
        else:
            tile = max(1, self.tile_px // binning)
            model = tiled_background(det, tile, scale=binning, offset=(binning - 1) / 2)
        return with_noise_floor(model, _floor(det, model.level)) if model.noise <= 0 else model

    def _measure(self, prepared: PreparedImage, regions: Regions, model: BackgroundModel,
                 noise_px: float) -> tuple[SpotMeasurements, NDArray]:
        """Measure the spots and apply the spot filters; returns the kept spots and the pixel
        noise at each."""
        level, _ = model.at(regions.x, regions.y)
        signal = prepared.data[regions.y, regions.x] - level
        if prepared.invalid is not None:
            signal[prepared.invalid[regions.y, regions.x]] = 0.0
        spots = measure_spots(regions, signal)
        peak_level, peak_noise = model.at(spots.peak_x, spots.peak_y)
        local_noise = noise_px * peak_noise / model.noise
        clutter = model.clutter_at(spots.peak_x, spots.peak_y)
        keep = self._filter(spots, local_noise, clutter, prepared.data, peak_level)
        return take_spots(spots, keep), local_noise[keep]

    def _filter(self, spots: SpotMeasurements, local_noise: NDArray, clutter: NDArray,
                data: NDArray, peak_level: NDArray) -> NDArray[np.bool_]:
        """The AND of all spot filters (see :mod:`.filters`), shape (N,)."""
        fraction = filters.peak_fraction(data, peak_level, spots.peak_x, spots.peak_y)
        keep = np.isfinite(spots.x) & (spots.flux > 0)
        keep &= filters.area_ok(spots.area_px, self.min_area_px, self.max_area_px)
        keep &= filters.peak_ok(spots.peak / local_noise, self.min_peak_snr)
        keep &= filters.elongation_ok(spots.elongation, self.max_elongation)
        keep &= filters.flatness_ok(spots.flatness, self.min_flatness)
        keep &= filters.hot_pixel_ok(fraction, self.max_peak_fraction)
        keep &= filters.clutter_ok(clutter, self.max_clutter)
        return keep

    def _to_detections(self, spots: SpotMeasurements, local_noise: NDArray, empty: Detections
                       ) -> Detections:
        """Sort brightest first, cut to ``max_stars`` and pack into :class:`Detections`."""
        order = np.argsort(-spots.flux, kind="stable")[: self.max_stars]
        spots, local_noise = take_spots(spots, order), local_noise[order]
        return Detections(
            x=spots.x, y=spots.y, flux=spots.flux,
            sigma_px=centroid_sigma(spots, local_noise, self.uncertainty),
            area_px=spots.area_px.astype(np.int64), peak=spots.peak, elongation=spots.elongation,
            background=empty.background, noise=empty.noise, width=empty.width, height=empty.height,
        )


def detect(image: NDArray, **settings) -> Detections:
    """Detect and centroid stars with a :class:`StarDetector` built from ``settings``.

    ``detect(image, sigma=4)`` is ``StarDetector(sigma=4).detect(image)``; see
    :class:`StarDetector` for the settings and :meth:`StarDetector.detect` for the result.
    """
    return StarDetector(**settings).detect(image)


def _floor(values: NDArray, level: float) -> float:
    """Noise floor for a noise-free (simulated) image: a millionth of the largest deviation
    from the background (0 when the image is constant)."""
    largest = float(np.fmax.reduce(np.abs(values - np.float32(level)), axis=None))  # NaN-free
    return NOISE_FLOOR_FRACTION * largest if np.isfinite(largest) else 0.0


def _check_positive(obj, names: tuple[str, ...], optional: bool = False) -> None:
    for name in names:
        value = getattr(obj, name)
        if optional and value is None:
            continue
        if not (isinstance(value, int | float | np.number) and math.isfinite(value) and value > 0):
            raise InvalidInputError(
                f"{name} must be a positive number{_or_none(optional)}, got {value!r}")


def _check_non_negative(obj, names: tuple[str, ...]) -> None:
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, int | float | np.number) and math.isfinite(value) and value >= 0):
            raise InvalidInputError(f"{name} must be a number >= 0, got {value!r}")


def _check_int(obj, names: tuple[str, ...], minimum: int, optional: bool = False) -> None:
    for name in names:
        value = getattr(obj, name)
        if optional and value is None:
            continue
        is_int = isinstance(value, int | np.integer) and not isinstance(value, bool)
        if not (is_int and value >= minimum):
            raise InvalidInputError(
                f"{name} must be an integer >= {minimum}{_or_none(optional)}, got {value!r}")


def _or_none(optional: bool) -> str:
    return " or None" if optional else ""
