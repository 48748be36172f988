"""A lost-in-space solve request, validated: the stars in search order, the nominal camera, what
is known of the focal length and the pixel aspect, the database range and the catalog epoch.

:func:`build_request` is what ``startrack.solve_stars`` and ``startrack.solve_image`` check their
arguments with; :class:`SolveRequest` is the :class:`.registry.MatchRequest` the matchers read.

Pixel aspect
    ``pixel_aspect`` is the height of a pixel on the sky over its width, ``fx / fy`` (1 for
    square pixels; about 1.9 for a sensor whose rows each span 1.9 pixel widths). Given as a
    number, the nominal camera gets ``fy = fx / pixel_aspect`` and the final fit keeps it; given
    as a range ``(lo, hi)``, the pattern search tries aspects across it
    (:func:`.quad_matcher.aspect_trials`) and the final fit frees it; not given, the search
    assumes square pixels and the final fit frees the aspect once enough stars are matched
    (:data:`.final_fit.MIN_STARS_FOR_ASPECT`), so a slightly anisotropic sensor is not biased.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera, focal_px_from_fov
from ..errors import InvalidInputError
from ._image_epoch import Epoch
from ._parity import Parity, check_parity
from ._registry import DEFAULT_FOV_RANGE_DEG

MIN_FOV_DEG = 0.5
"""The narrowest horizontal field of view (deg) a solve may be given or may search: a small
telescope's (below it Hipparcos has too few stars)."""

MAX_FOV_DEG = 150.0
"""The widest horizontal field of view (deg) a solve may be given or may search: the widest
rectilinear lenses' (a 12 mm lens on a full-frame camera spans 113 deg, a phone's ultra-wide about
110). A pinhole image of 150 deg reaches 77 deg off axis in its 3:2 corners. Simulated frames of
110-150 deg with such lenses' barrel solve within 2 px in most cases, a few with a poor fit of the
lens (``benchmarks/realdata_benchmark.py --wide``, docs/identification.md); at 160 deg some
frames did not solve."""

FOV_DEG_TOLERANCE = 0.03
"""A given ``fov_deg`` is trusted to this fraction; the solve refines it."""

PIXEL_ASPECT_RANGE = (0.1, 10.0)
"""Pixel aspects (fx / fy) accepted: pixels from a tenth to ten times as high as they are wide."""


@dataclass(frozen=True)
class SolveRequest:
    """A validated solve request (module docstring).

    Attributes
    ----------
    x, y : ndarray, shape (N,)
        Star positions (pixels) in search order: brightest first, point sources first for an image.
    rows : ndarray of int, shape (N,)
        Index of each star in the caller's list.
    camera : Camera
        The nominal camera (focal length at the middle of the range, the pixel aspect).
    focal_range : (float, float) or None
        Focal lengths fx to search (pixels); None when the camera is calibrated.
    fov_range_deg : (float, float)
        Horizontal fields of view of the database to use.
    epoch : Epoch
        Catalog epoch and its source.
    prior_rot, prior_sigma_deg
        Prior attitude and its 1-sigma per axis (for the overlay matcher).
    aspect_range : (float, float) or None
        Pixel aspects to search; None: the camera's.
    fit_aspect : bool
        The final fit frees the pixel aspect.
    parity : {"normal", "mirrored", "either"}
        Which image parities to search (:mod:`._parity`); ``camera`` is never ``mirrored``.
    """

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    rows: NDArray[np.int64]
    camera: Camera
    focal_range: tuple[float, float] | None
    fov_range_deg: tuple[float, float]
    epoch: Epoch
    prior_rot: Rotation | None = None
    prior_sigma_deg: float = 1.0
    aspect_range: tuple[float, float] | None = None
    fit_aspect: bool = False
    parity: Parity = "normal"

    @property
    def epoch_jyear(self) -> float:
        return self.epoch.jyear


def check_fov_deg(fov: float, name: str) -> float:
    """``fov`` as a float if it is a field of view startrack can solve (:data:`MIN_FOV_DEG` to
    :data:`MAX_FOV_DEG`); else an InvalidInputError naming ``name``."""
    try:
        fov = float(fov)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be a field of view in deg (a number), got {fov!r}") from None
    if not (math.isfinite(fov) and MIN_FOV_DEG <= fov <= MAX_FOV_DEG):
        raise InvalidInputError(f"{name} must be a field of view between {MIN_FOV_DEG:g} and {MAX_FOV_DEG:g} deg, "
                                f"got {fov:g}")
    return fov


def check_pixel_aspect(pixel_aspect, name: str = "pixel_aspect") -> tuple[float | None, tuple[float, float] | None]:
    """(fixed aspect, aspect range to search) from a ``pixel_aspect`` argument: None, a number
    or a pair (lo, hi); either may be None. Raises InvalidInputError naming ``name``."""
    if pixel_aspect is None:
        return None, None
    values = np.atleast_1d(np.asarray(pixel_aspect, dtype=object)).ravel()
    lo, hi = PIXEL_ASPECT_RANGE
    try:
        numbers = [float(v) for v in values if not isinstance(v, bool | str)]
    except (TypeError, ValueError):
        numbers = []
    if len(numbers) != values.size or values.size not in (1, 2) or not all(lo <= v <= hi for v in numbers):
        raise InvalidInputError(f"{name} must be a pixel's height over its width (fx / fy, {lo:g} to {hi:g}) "
                                f"or a range (low, high) of them to search, got {pixel_aspect!r}")
    if len(numbers) == 1:
        return numbers[0], None
    if numbers[0] > numbers[1]:
        raise InvalidInputError(f"{name} range must be (low, high) with low <= high, got {pixel_aspect!r}")
    return None, (numbers[0], numbers[1])


def _fov_pair(fov_range_deg) -> tuple[float, float]:
    values = np.asarray(fov_range_deg, dtype=object).ravel()
    if isinstance(fov_range_deg, str) or values.size != 2:
        raise InvalidInputError(f"fov_range_deg must be a pair (low, high) in deg, got {fov_range_deg!r}")
    return check_fov_deg(values[0], "fov_range_deg low"), check_fov_deg(values[1], "fov_range_deg high")


def _focal_setup(width, height, fov_deg, fov_range_deg, camera, aspect: float):
    """Nominal camera, focal range (None: fixed) and the FOV range for the database."""
    if camera is not None:
        return camera, None, (camera.fov_deg, camera.fov_deg)
    if fov_deg is not None:
        fov = check_fov_deg(fov_deg, "fov_deg")
        lo, hi = fov * (1 - FOV_DEG_TOLERANCE), fov * (1 + FOV_DEG_TOLERANCE)
    else:
        lo, hi = _fov_pair(fov_range_deg if fov_range_deg is not None else DEFAULT_FOV_RANGE_DEG)
        if lo > hi:
            raise InvalidInputError(f"fov_range_deg must be (low, high) with low <= high, got ({lo:g}, {hi:g})")
    f_lo, f_hi = focal_px_from_fov(width, math.radians(hi)), focal_px_from_fov(width, math.radians(lo))
    fx = math.sqrt(f_lo * f_hi)
    return _nominal_camera(int(width), int(height), fx, fx / aspect), (f_lo, f_hi), (lo, hi)


@functools.lru_cache(maxsize=64)
def _nominal_camera(width: int, height: int, fx: float, fy: float) -> Camera:
    """The pinhole Camera of these settings, built (and checked) once: a Camera is immutable, and a
    batch of images or star lists from one camera asks for the same nominal camera every time."""
    return Camera(width=width, height=height, fx=fx, fy=fy)


def check_distinct(x: NDArray, y: NDArray) -> None:
    """Two stars at exactly the same position make degenerate patterns: refuse them. (One sort of x;
    only when two stars share an x, one of the positions as complex numbers, ordered by x then y;
    the pair is looked up only when there is one.)"""
    by_x = np.sort(x)
    if not (by_x[1:] == by_x[:-1]).any():  # no two share an x (the usual case): no pair to look for
        return
    z = np.sort(x + 1j * y)
    if not np.any(z[1:] == z[:-1]):
        return
    order = np.lexsort((y, x))
    same = (np.diff(x[order]) == 0) & (np.diff(y[order]) == 0)
    k = int(np.flatnonzero(same)[0])
    i, j = sorted(int(v) for v in order[k:k + 2])
    raise InvalidInputError(f"stars {i} and {j} are at the same position ({x[i]:g}, {y[i]:g}); "
                            "give each star once")


def star_arrays(x, y, flux, width, height) -> tuple[NDArray, NDArray, NDArray]:
    """Validated coordinates, brightest first, and the input row of each."""
    x, y = _coordinates(x, "x"), _coordinates(y, "y")
    if x.shape != y.shape:
        raise InvalidInputError(f"x and y must have the same length, got {x.size} and {y.size}")
    if x.size and not _inside(x, y, width, height):  # NaN or inf fail it: say which check they fail
        _check_inside(x, y, width, height)
    check_distinct(x, y)
    if flux is not None:
        flux = _coordinates(flux, "flux")
        if flux.shape != x.shape or not np.isfinite(flux).all():
            raise InvalidInputError("flux must be finite and as long as x and y")
        order = np.argsort(-flux, kind="stable")
        return x[order], y[order], order
    return x, y, np.arange(x.size)


def _inside(x: NDArray, y: NDArray, width, height) -> bool:
    """Whether the stars ``x``, ``y`` (N >= 1,) are finite numbers inside the image (four reductions:
    a NaN makes its extreme NaN, and an inf lies outside)."""
    return bool(x.min() >= -0.5 and y.min() >= -0.5 and x.max() <= width - 0.5 and y.max() <= height - 0.5)


def _check_inside(x: NDArray, y: NDArray, width, height) -> None:
    """Refuse stars that are not finite numbers, or one outside the image (naming the first)."""
    if not (np.isfinite(x).all() and np.isfinite(y).all()):
        raise InvalidInputError("star coordinates must be finite numbers (got NaN or inf)")
    outside = (x < -0.5) | (y < -0.5) | (x > width - 0.5) | (y > height - 0.5)
    i = int(np.flatnonzero(outside)[0])
    raise InvalidInputError(f"star {i} at ({x[i]:g}, {y[i]:g}) lies outside the {width} x {height} image "
                            f"(valid: -0.5 <= x <= {width - 0.5}, -0.5 <= y <= {height - 0.5})")


def _coordinates(values, name: str) -> NDArray[np.float64]:
    """A 1-D float array of ``values``; refuses a masked array with masked entries (say which),
    None, complex numbers and arrays of more than one dimension (a table or an image given by
    mistake, which flattening would turn into a list of the wrong numbers); a column or a row,
    (N, 1) or (1, N), is one dimension."""
    if np.ma.isMaskedArray(values) and np.ma.count_masked(values):
        raise InvalidInputError(f"{name} has {np.ma.count_masked(values)} masked entries; "
                                "drop those stars (or fill them) before solving")
    data = None if values is None else np.asarray(np.ma.getdata(values))
    if data is not None and data.ndim == 2 and 1 in data.shape:
        data = data.ravel()
    if data is None or data.dtype.kind not in "biuf" or data.ndim > 1:
        what = "None" if data is None else f"an array of shape {data.shape}" if data.ndim > 1 else repr(values)
        raise InvalidInputError(f"{name} must be real numbers in one dimension (one per star, shape (N,)), "
                                f"got {what:.80}")
    return data.astype(float).ravel()


def _check_size(width, height) -> None:
    for name, value in (("width", width), ("height", height)):
        if not (isinstance(value, int | np.integer) and not isinstance(value, bool) and value >= 2):
            raise InvalidInputError(f"{name} must be an integer number of pixels >= 2, got {value!r}")


def build_request(x, y, *, width, height, fov_deg, fov_range_deg, camera, flux, epoch: Epoch,
                  pixel_aspect=None, parity=None, default_parity: Parity = "normal") -> SolveRequest:
    """Check a solve's arguments (as :func:`startrack.solve_stars` documents them) and build
    the request; raises InvalidInputError naming the argument that is wrong. ``parity`` None
    takes the camera's, else ``default_parity`` (:func:`.parity.check_parity`)."""
    if camera is not None and not isinstance(camera, Camera):
        raise InvalidInputError(f"camera must be a startrack.Camera, got {type(camera).__name__}")
    parity, camera = check_parity(parity, camera, default_parity)
    if camera is not None:
        width, height = camera.width, camera.height
    _check_size(width, height)
    if fov_deg is not None and fov_range_deg is not None:
        raise InvalidInputError("give fov_deg or fov_range_deg, not both")
    if camera is not None and (fov_deg is not None or fov_range_deg is not None):
        raise InvalidInputError("a camera fixes the field of view: give camera or fov_deg / fov_range_deg, not both")
    if camera is not None and pixel_aspect is not None:
        raise InvalidInputError("a camera fixes the pixel aspect (its fx / fy): give camera or pixel_aspect, not both")
    aspect, aspect_range = check_pixel_aspect(pixel_aspect)
    xs, ys, rows = star_arrays(x, y, flux, width, height)
    start = aspect if aspect is not None else (math.sqrt(aspect_range[0] * aspect_range[1]) if aspect_range else 1.0)
    nominal, focal_range, fov_range = _focal_setup(width, height, fov_deg, fov_range_deg, camera, start)
    fit_aspect = camera is None and aspect is None
    return SolveRequest(xs, ys, rows, nominal, focal_range, fov_range, epoch, aspect_range=aspect_range,
                        fit_aspect=fit_aspect, parity=parity)
