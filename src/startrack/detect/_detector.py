"""The configured star detector: every detection method selectable by name, one interface.

See the package docstring of :mod:`startrack.detect` for the pipeline and its defaults, and
``docs/detection.md`` for the methods and how close each comes to the Cramér-Rao bound.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError
from ..io import channel_index
from ..results import Detections
from . import _settings_checks as checks
from ._blocks import detect_in_strips
from ._centroid import UNCERTAINTY_MODELS, UncertaintyModel
from ._centroiders import CENTROIDERS, CentroidMethod
from ._denoise import DENOISE_METHODS
from ._details import DetectionDetails
from ._pipeline import detect_frame
from ._predictive import WindowDetections, measure_windows
from ._smooth import KERNELS

BackgroundMode = Literal["tiled", "global"]
ThresholdMethod = Literal["ksigma", "dynamic", "prefilter-window", "prefilter-grid"]
GroupingMethod = Literal["label8", "region-grow"]
BACKGROUND_MODES: tuple[str, ...] = get_args(BackgroundMode)
THRESHOLDS: tuple[str, ...] = get_args(ThresholdMethod)
GROUPINGS: tuple[str, ...] = get_args(GroupingMethod)
DEFAULT_MAX_BLOCK_PX = 1 << 24


@dataclass(frozen=True)
class StarDetector:
    """Star detector with fixed settings (validated once, when constructed).

    Background and noise
        dark_frame : ndarray (H, W) or None -- dark or median (fixed-pattern) frame to subtract
        (:mod:`._dark`). dark_columns : (leading, trailing) -- dark reference columns per row
        (Jacobs 1995), subtracted row by row and cut off (x stays in the full frame's pixels).
        background : {"tiled", "global"} -- local (per ``tile_px`` tile, interpolated) or
        global level and noise; with ``threshold="ksigma"`` these are the local and global
        k-sigma thresholds.
    Noise removal (optional, :mod:`._denoise`)
        denoise : {"none", "gaussian", "diffusion"}; denoise_sigma_px; diffusion_iterations;
        diffusion_kappa_sigma (the edge threshold K in noise units). Stacking:
        :func:`startrack.detect.stack_frames` before detection.
    Detection image (:mod:`._smooth`)
        binning, kernel {"binomial", "box"}, kernel_px (odd).
    Threshold (:mod:`._threshold`, :mod:`._prefilters`)
        threshold : {"ksigma", "dynamic", "prefilter-window", "prefilter-grid"}.
        sigma -- k of the detection image (the lowest k of "dynamic"); grow_sigma -- the
        level spots are grown to; fine_sigma -- k of the full-resolution pass for sharp stars
        (:mod:`._fine_pass`; None: off); target_stars, max_sigma -- the dynamic threshold's target
        count and highest k; pixel_sigma, prefilter_count -- single-pixel k and the count of
        25 of Huffman 2006's 5 x 5 pre-filters (which work on full-resolution pixels).
    Grouping (:mod:`._label`, :mod:`._region_grow`)
        grouping : {"label8", "region-grow"}; jump_px -- the region growing's scan step;
        deblend; reject_edge; min_area_px, max_area_px (full-resolution pixels);
        min_packing -- the proximity filter (0 = off).
    Spot filters (:mod:`._filters`, :mod:`._shape`)
        min_peak_snr, max_elongation (the eccentricity test: e = sqrt(1 - 1 / elongation^2)),
        min_flatness, max_peak_fraction (hot pixels), max_clutter; smear_px (dx, dy),
        smear_tolerance_px, smear_angle_deg, max_axis_difference_px -- Jacobs 1995's shape test.
    Centroid (:mod:`._centroiders`)
        centroid : {"peak", "area", "weighted", "weighted-raw", "windowed", "mle"};
        psf_sigma_px -- known PSF width (None: estimated; fitted by "mle");
        window_half_px -- window of the window methods (None: ceil(3 sigma) + 1);
        gain_e_per_adu -- adds the stars' shot noise to the weights and errors (None: the
        background noise only); uncertainty {"propagated", "eq4.2"} -- the method's own error
        (propagated noise or fit covariance) or Huffman 2006's eq. 4.2; mag_zero_point -- of the
        instrument magnitude (:mod:`._magnitude`).
    Output
        channel : {None, "r", "g", "b", 0, 1, 2} -- colour plane (None: R + G + B);
        max_stars -- keep only the brightest; max_block_px -- frames larger than this are
        processed in strips (:mod:`._blocks`).
    """

    dark_frame: NDArray | None = field(default=None, repr=False, compare=False)
    dark_columns: tuple[int, int] = (0, 0)
    background: BackgroundMode = "tiled"
    tile_px: int = 32
    denoise: str = "none"
    denoise_sigma_px: float = 1.0
    diffusion_iterations: int = 10
    diffusion_kappa_sigma: float = 3.0
    binning: int = 2
    kernel: str = "binomial"
    kernel_px: int = 3
    threshold: ThresholdMethod = "ksigma"
    sigma: float = 5.0
    grow_sigma: float = 3.0
    fine_sigma: float | None = 6.5
    target_stars: int = 30
    max_sigma: float = 1000.0
    pixel_sigma: float = 2.0
    prefilter_count: int = 9
    grouping: GroupingMethod = "label8"
    jump_px: int = 3
    deblend: bool = True
    reject_edge: bool = True
    min_area_px: int = 4
    max_area_px: int | None = 4096
    min_packing: float = 0.0
    min_peak_snr: float = 0.0
    max_elongation: float | None = 5.0
    min_flatness: float = 0.0
    max_peak_fraction: float | None = 0.75
    max_clutter: float | None = 2.5
    smear_px: tuple[float, float] | None = None
    smear_tolerance_px: float = 2.0
    smear_angle_deg: float = 30.0
    max_axis_difference_px: float | None = None
    centroid: CentroidMethod = "windowed"
    psf_sigma_px: float | None = None
    window_half_px: int | None = None
    gain_e_per_adu: float | None = None
    uncertainty: UncertaintyModel = "propagated"
    mag_zero_point: float = 0.0
    channel: str | int | None = None
    max_stars: int | None = None
    max_block_px: int = DEFAULT_MAX_BLOCK_PX

    def __post_init__(self) -> None:
        checks.check_positive(self, ("sigma", "grow_sigma", "denoise_sigma_px",
                                     "diffusion_kappa_sigma", "max_sigma", "pixel_sigma",
                                     "smear_tolerance_px", "smear_angle_deg"))
        checks.check_positive(self, ("fine_sigma", "max_elongation", "max_peak_fraction", "max_clutter",
                                     "psf_sigma_px", "gain_e_per_adu", "max_axis_difference_px"),
                              optional=True)
        checks.check_int(self, ("binning", "kernel_px", "tile_px", "min_area_px", "jump_px",
                                "target_stars", "diffusion_iterations"), minimum=1)
        checks.check_int(self, ("prefilter_count",), minimum=1)
        checks.check_int(self, ("max_block_px",), minimum=1024)
        checks.check_int(self, ("max_area_px", "max_stars", "window_half_px"), minimum=1,
                         optional=True)
        checks.check_non_negative(self, ("min_peak_snr", "min_flatness", "min_packing"))
        if not isinstance(self.mag_zero_point, int | float) or not np.isfinite(self.mag_zero_point):
            raise InvalidInputError(f"mag_zero_point must be a finite number, got "
                                    f"{self.mag_zero_point!r}")
        if self.kernel_px % 2 == 0:
            raise InvalidInputError(
                f"kernel_px must be an odd integer (1, 3, 5...), got {self.kernel_px}")
        if self.prefilter_count > 25:
            raise InvalidInputError(f"prefilter_count must be 1..25, got {self.prefilter_count}")
        for name, choices in (("kernel", KERNELS), ("background", BACKGROUND_MODES),
                              ("uncertainty", UNCERTAINTY_MODELS), ("threshold", THRESHOLDS),
                              ("grouping", GROUPINGS), ("centroid", CENTROIDERS),
                              ("denoise", DENOISE_METHODS)):
            checks.check_choice(self, name, choices)
        checks.check_pair(self, "dark_columns", optional=False, integer=True)
        checks.check_pair(self, "smear_px", optional=True, integer=False)
        checks.check_dark(self.dark_frame)
        channel_index(self.channel)
        checks.check_bool(self, ("reject_edge", "deblend"))

    def settings(self) -> dict:
        """The settings as a plain dict (for logs and result files; the dark frame as its
        shape)."""
        out = asdict(self)
        if self.dark_frame is not None:
            out["dark_frame"] = f"array{np.shape(self.dark_frame)}"
        return out

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
            Bad shape, dtype or size, no finite pixel, or a dark frame of another shape.
        """
        return self.detect_details(image).detections

    def detect_details(self, image: NDArray) -> DetectionDetails:
        """As :meth:`detect`, with the instrument magnitude, the spot shape, the PSF width and
        the threshold used (:class:`startrack.detect.DetectionDetails`)."""
        array = np.asarray(image)
        h, w = array.shape[:2] if array.ndim >= 2 else (0, 0)
        if h * w > self.max_block_px and array.ndim in (2, 3):
            return detect_in_strips(self, array)
        return detect_frame(self, array, self.dark_frame)

    def measure_windows(self, image: NDArray, x: ArrayLike, y: ArrayLike,
                        half_width_px: int = 6) -> WindowDetections:
        """Predictive centroiding: find and centroid stars only in square windows of
        half-width ``half_width_px`` centred on the predicted positions (x, y) (Samaan 2002;
        :mod:`._predictive`). The background of each window is its outer ring.

        Returns
        -------
        WindowDetections
            Detections (brightest first) and the index of the prediction each belongs to;
            predictions with no star in their window are absent.
        """
        x = np.atleast_1d(np.asarray(x, dtype=np.float64))
        y = np.atleast_1d(np.asarray(y, dtype=np.float64))
        if x.shape != y.shape or x.ndim != 1 or not np.all(np.isfinite(x) & np.isfinite(y)):
            raise InvalidInputError("x and y must be 1-D arrays of one length of finite "
                                    "predicted positions")
        if not (isinstance(half_width_px, int | np.integer) and half_width_px >= 2):
            raise InvalidInputError(f"half_width_px must be an integer >= 2, got {half_width_px!r}")
        if x.size == 0:
            return WindowDetections()
        return measure_windows(self, image, x, y, int(half_width_px))


def detect(image: NDArray, **settings) -> Detections:
    """Detect and centroid stars with a :class:`StarDetector` built from ``settings``.

    ``detect(image, sigma=4, centroid="mle")`` is
    ``StarDetector(sigma=4, centroid="mle").detect(image)``; see :class:`StarDetector` for the
    settings and :meth:`StarDetector.detect` for the result.
    """
    return StarDetector(**settings).detect(image)
