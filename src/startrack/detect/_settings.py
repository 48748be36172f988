"""The settings of a star detection: every field of :class:`StarDetector`, validated once.

The pipeline stages (:mod:`._pipeline`, :mod:`._blocks`, :mod:`._predictive`) read a
:class:`DetectionSettings`; :class:`startrack.detect.StarDetector` (:mod:`._detector`) is the
facade that holds the same settings (it subclasses this class) and runs those stages. The stages
thus import this module, never the facade's.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError, check_bool, check_int, check_non_negative, check_positive
from ..io import channel_index
from . import _settings_checks as checks
from ._centroid import UNCERTAINTY_MODELS, UncertaintyModel
from ._centroiders import CENTROIDERS, CentroidMethod
from ._denoise import DENOISE_METHODS, DenoiseMethod
from ._smooth import KERNELS, SmoothingKernel

BackgroundMode = Literal["tiled", "global"]
ThresholdMethod = Literal["ksigma", "dynamic", "prefilter-window", "prefilter-grid"]
GroupingMethod = Literal["label8", "region-grow"]
BACKGROUND_MODES: tuple[str, ...] = get_args(BackgroundMode)
THRESHOLDS: tuple[str, ...] = get_args(ThresholdMethod)
GROUPINGS: tuple[str, ...] = get_args(GroupingMethod)
DEFAULT_MAX_BLOCK_PX = 1 << 24
UPPER_LIMITS: dict[str, float] = {"kernel_px": 51, "window_half_px": 100, "denoise_sigma_px": 50.0,
                                  "diffusion_iterations": 1000, "sigma": 1e6, "grow_sigma": 1e6,
                                  "pixel_sigma": 1e6, "max_sigma": 1e6}
"""The largest values of the settings whose cost grows with them without end: a smoothing kernel of 51
px, a centroid window of 201 x 201 px and a denoising Gaussian of sd 50 px (0.4 s on a 1 MP frame) hold
defocused stars many times wider than a star tracker's; 1000 diffusion iterations take about 20 s on a
1 MP frame (0.37 s for 20). Past them one detection ran for hours (a kernel of 1,000,001 px) or asked
for more memory than exists (a window of 200,001 px). Thresholds stop at a million noise units: a
threshold of 1e300 overflowed the detection image's float32."""


@dataclass(frozen=True)
class DetectionSettings:
    """The settings of a star detection (validated once, when constructed); what the pipeline's
    stages read. :class:`StarDetector` holds the same fields and runs the detection.

    Background and noise
        dark_frame : ndarray (H, W) or None -- dark or median (fixed-pattern) frame to subtract
        (:mod:`._dark`). dark_columns : (leading, trailing) -- dark reference columns per row
        (Jacobs 1995), subtracted row by row and cut off (x stays in the full frame's pixels).
        background : {"tiled", "global"} -- local (per ``tile_px`` tile, interpolated) or
        global level and noise; with ``threshold="ksigma"`` these are the local and global
        k-sigma thresholds. compression_noise -- a lossy compression's noise floor, image
        units (0: none; :meth:`StarDetector.for_image` sets it for a JPEG): the clutter filter's
        clean sky is at least this, and so is the threshold's noise where a crowd of spots passes
        the threshold without it (:mod:`._compression`).
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

    Raises
    ------
    InvalidInputError
        A setting out of its range or not one of its names, naming the setting, the value and
        what is valid.
    """

    dark_frame: NDArray | None = field(default=None, repr=False, compare=False)
    dark_columns: tuple[int, int] = (0, 0)
    background: BackgroundMode = "tiled"
    tile_px: int = 32
    compression_noise: float = 0.0
    denoise: DenoiseMethod = "none"
    denoise_sigma_px: float = 1.0
    diffusion_iterations: int = 10
    diffusion_kappa_sigma: float = 3.0
    binning: int = 2
    kernel: SmoothingKernel = "binomial"
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
        self._check_numbers()
        for name, choices in (("kernel", KERNELS), ("background", BACKGROUND_MODES),
                              ("uncertainty", UNCERTAINTY_MODELS), ("threshold", THRESHOLDS),
                              ("grouping", GROUPINGS), ("centroid", CENTROIDERS),
                              ("denoise", DENOISE_METHODS)):
            checks.check_choice(self, name, choices)
        checks.check_pair(self, "dark_columns", optional=False, integer=True)
        checks.check_pair(self, "smear_px", optional=True, integer=False)
        checks.check_dark(self.dark_frame)
        channel_index(self.channel)
        check_bool(self, ("reject_edge", "deblend"))

    def _check_numbers(self) -> None:
        """The numeric settings are in their ranges (InvalidInputError naming the first that is not)."""
        check_positive(self, ("sigma", "grow_sigma", "denoise_sigma_px", "diffusion_kappa_sigma", "max_sigma",
                              "pixel_sigma", "smear_tolerance_px", "smear_angle_deg"))
        check_positive(self, ("fine_sigma", "max_elongation", "max_peak_fraction", "max_clutter", "psf_sigma_px",
                              "gain_e_per_adu", "max_axis_difference_px"), optional=True)
        check_int(self, ("binning", "kernel_px", "tile_px", "min_area_px", "jump_px", "target_stars",
                         "diffusion_iterations"), minimum=1)
        check_int(self, ("prefilter_count",), minimum=1)
        check_int(self, ("max_block_px",), minimum=1024)
        check_int(self, ("max_area_px", "max_stars", "window_half_px"), minimum=1, optional=True)
        check_non_negative(self, ("min_peak_snr", "min_flatness", "min_packing", "compression_noise"))
        if not isinstance(self.mag_zero_point, int | float) or not np.isfinite(self.mag_zero_point):
            raise InvalidInputError(f"mag_zero_point must be a finite number, got "
                                    f"{self.mag_zero_point!r}")
        for name, high in UPPER_LIMITS.items():
            value = getattr(self, name)
            if value is not None and value > high:
                raise InvalidInputError(f"{name} must be at most {high:g}, got {value!r}")
        if self.kernel_px % 2 == 0:
            raise InvalidInputError(
                f"kernel_px must be an odd integer (1, 3, 5...), got {self.kernel_px}")
        if self.prefilter_count > 25:
            raise InvalidInputError(f"prefilter_count must be 1..25, got {self.prefilter_count}")

    def settings(self) -> dict:
        """The settings as a plain dict (for logs and result files; the dark frame as its
        shape)."""
        out = asdict(self)
        if self.dark_frame is not None:
            out["dark_frame"] = f"array{np.shape(self.dark_frame)}"
        return out
