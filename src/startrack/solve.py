"""Lost-in-space solving: a star list or an image in, an :class:`AttitudeSolution` out.

This module only orchestrates: it validates the input, picks the pattern database for the field
of view, calls the matcher (:mod:`startrack.identify`), refines the match on all stars, and
computes the QUEST attitude with its covariance (:mod:`startrack.attitude`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np
from astropy.time import Time
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from .attitude.covariance import covariance_batch
from .camera import Camera, focal_px_from_fov
from .catalog import load_catalog
from .errors import InvalidInputError
from .frames import angle_between, radec_roll_from_rotation
from .identify.candidate import Candidate
from .identify.field_stars import FieldStars
from .identify.final_fit import settle_matches
from .identify.refine import wahba_equal_weights
from .identify.registry import DEFAULT_FOV_RANGE_DEG, MATCHERS, prepare_matcher
from .results import AttitudeSolution, StarMatches, Status
from .units import ARCSEC

FOV_DEG_TOLERANCE = 0.03
"""A given ``fov_deg`` is trusted to this fraction; the solve refines it."""

DEFAULT_EPOCH_JYEAR = 2000.0


@dataclass(frozen=True)
class _Problem:
    """A validated solve request."""

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    rows: NDArray[np.int64]
    camera: Camera
    focal_range: tuple[float, float] | None
    fov_range_deg: tuple[float, float]
    epoch_jyear: float
    prior_rot: Rotation | None = None
    prior_sigma_deg: float = 1.0


def epoch_jyear(epoch) -> float:
    """A catalog epoch as a Julian year (TDB): None gives J2000.0; accepts astropy Time or a year."""
    if epoch is None:
        return DEFAULT_EPOCH_JYEAR
    if isinstance(epoch, Time):
        return float(epoch.tdb.jyear)
    value = float(epoch)
    if not (1000.0 < value < 3000.0):
        raise InvalidInputError(f"epoch must be an astropy Time or a Julian year such as 2025.5, got {epoch!r}")
    return value


def check_fov_deg(fov: float, name: str) -> float:
    """``fov`` as a float if it is a field of view startrack can solve (0.5 to 100 deg); else an
    InvalidInputError naming ``name``."""
    fov = float(fov)
    if not (math.isfinite(fov) and 0.5 <= fov <= 100.0):
        raise InvalidInputError(f"{name} must be a field of view between 0.5 and 100 deg, got {fov:g}")
    return fov


def _focal_setup(width, height, fov_deg, fov_range_deg, camera):
    """Nominal camera, focal range (None: fixed) and the FOV range for the database."""
    if camera is not None:
        return camera, None, (camera.fov_deg, camera.fov_deg)
    if fov_deg is not None:
        fov = check_fov_deg(fov_deg, "fov_deg")
        lo, hi = fov * (1 - FOV_DEG_TOLERANCE), fov * (1 + FOV_DEG_TOLERANCE)
    else:
        lo, hi = _fov_pair(fov_range_deg if fov_range_deg is not None else DEFAULT_FOV_RANGE_DEG)
        lo, hi = check_fov_deg(lo, "fov_range_deg low"), check_fov_deg(hi, "fov_range_deg high")
        if lo > hi:
            raise InvalidInputError(f"fov_range_deg must be (low, high) with low <= high, got ({lo:g}, {hi:g})")
    f_lo, f_hi = focal_px_from_fov(width, math.radians(hi)), focal_px_from_fov(width, math.radians(lo))
    nominal = Camera(width=int(width), height=int(height), fx=math.sqrt(f_lo * f_hi))
    return nominal, (f_lo, f_hi), (lo, hi)


def _fov_pair(fov_range_deg) -> tuple[float, float]:
    values = np.asarray(fov_range_deg, dtype=object).ravel()
    if isinstance(fov_range_deg, str) or values.size != 2:
        raise InvalidInputError(f"fov_range_deg must be a pair (low, high) in deg, got {fov_range_deg!r}")
    return float(values[0]), float(values[1])


def _check_distinct(x: NDArray, y: NDArray) -> None:
    """Two stars at exactly the same position make degenerate patterns: refuse them."""
    order = np.lexsort((y, x))
    same = (np.diff(x[order]) == 0) & (np.diff(y[order]) == 0)
    if np.any(same):
        k = int(np.flatnonzero(same)[0])
        i, j = sorted(int(v) for v in order[k:k + 2])
        raise InvalidInputError(f"stars {i} and {j} are at the same position ({x[i]:g}, {y[i]:g}); "
                                "give each star once")


def _star_arrays(x, y, flux, width, height) -> tuple[NDArray, NDArray, NDArray]:
    """Validated coordinates, brightest first, and the input row of each."""
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if x.shape != y.shape:
        raise InvalidInputError(f"x and y must have the same length, got {x.size} and {y.size}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise InvalidInputError("star coordinates must be finite numbers (got NaN or inf)")
    outside = (x < -0.5) | (y < -0.5) | (x > width - 0.5) | (y > height - 0.5)
    if np.any(outside):
        i = int(np.flatnonzero(outside)[0])
        raise InvalidInputError(f"star {i} at ({x[i]:g}, {y[i]:g}) lies outside the {width} x {height} image "
                                f"(valid: -0.5 <= x <= {width - 0.5}, -0.5 <= y <= {height - 0.5})")
    _check_distinct(x, y)
    if flux is not None:
        flux = np.asarray(flux, dtype=float).ravel()
        if flux.shape != x.shape or not np.all(np.isfinite(flux)):
            raise InvalidInputError("flux must be finite and as long as x and y")
        order = np.argsort(-flux, kind="stable")
        return x[order], y[order], order
    return x, y, np.arange(x.size)


def _problem(x, y, width, height, fov_deg, fov_range_deg, camera, flux, epoch) -> _Problem:
    if camera is not None:
        width, height = camera.width, camera.height
    for name, value in (("width", width), ("height", height)):
        if not (isinstance(value, int | np.integer) and value >= 2):
            raise InvalidInputError(f"{name} must be an integer number of pixels >= 2, got {value!r}")
    if fov_deg is not None and fov_range_deg is not None:
        raise InvalidInputError("give fov_deg or fov_range_deg, not both")
    if camera is not None and (fov_deg is not None or fov_range_deg is not None):
        raise InvalidInputError("a camera fixes the field of view: give camera or fov_deg / fov_range_deg, not both")
    xs, ys, rows = _star_arrays(x, y, flux, width, height)
    nominal, focal_range, fov_range = _focal_setup(width, height, fov_deg, fov_range_deg, camera)
    return _Problem(xs, ys, rows, nominal, focal_range, fov_range, epoch_jyear(epoch))


def _solution(problem: _Problem, stars: FieldStars, cand: Candidate, t0: float) -> AttitudeSolution:
    """The solution from a verified candidate: refined fit, then the Wahba attitude of all matched
    stars (Davenport's q-method: the same optimum as QUEST; one compiled 4 x 4 eigen-decomposition,
    :func:`.identify.refine.wahba_equal_weights`; both solvers are in :mod:`startrack.attitude`) with the
    QUEST measurement-model covariance (seed 000 §6.1.3)."""
    fit = settle_matches(problem.x, problem.y, stars, cand, problem.focal_range)
    camera, img, rows, ref, res_px = fit.camera, fit.image_index, fit.catalog_rows, fit.ref_icrs, fit.residual_px
    observed = camera.pixel_to_vector(problem.x[img], problem.y[img])
    n = len(img)
    sigma_rad = max(math.sqrt(float(res_px @ res_px) / n), 0.05) / camera.fx
    quat, matrix = wahba_equal_weights(observed, ref)
    rot = Rotation.from_quat(quat)
    residuals = angle_between(ref @ matrix.T, observed) / ARCSEC
    ra, dec, roll = radec_roll_from_rotation(rot)
    matches = StarMatches(status=Status.OK, det_index=problem.rows[img].astype(np.int64),
                          hip=load_catalog().hip[rows].astype(np.int64), cat_vectors=ref,
                          false_match_prob=cand.false_match_prob)
    return AttitudeSolution(
        status=Status.OK, rot_cam_from_icrs=rot,
        covariance_rad2=covariance_batch(observed[None], np.full((1, n), sigma_rad))[0],  # >= 3 stars, spread
        ra_deg=math.degrees(ra), dec_deg=math.degrees(dec), roll_deg=math.degrees(roll),
        fov_deg=camera.fov_deg, camera=camera, matches=matches, residuals_arcsec=residuals,
        false_match_prob=cand.false_match_prob, solve_time_s=time.perf_counter() - t0)


def solve_stars(x: ArrayLike, y: ArrayLike, *, width: int | None = None, height: int | None = None,
                fov_deg: float | None = None, fov_range_deg: tuple[float, float] | None = None,
                camera: Camera | None = None, flux: ArrayLike | None = None, epoch=None,
                method: str = "quads", options: object | None = None,
                prior_rot_cam_from_icrs: Rotation | None = None, prior_sigma_deg: float = 1.0) -> AttitudeSolution:
    """Lost-in-space attitude from a list of star centroids.

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Star centroids in our pixel convention (0-based pixel centres, x = column), brightest
        first (or give ``flux`` and they are sorted by it).
    width, height : int
        Image size in pixels (taken from ``camera`` when one is given).
    fov_deg : float, optional
        Horizontal field of view, trusted to +-3 % and refined.
    fov_range_deg : (float, float), optional
        Range of horizontal fields of view to search; default (5, 35) when neither is given.
    camera : Camera, optional
        A calibrated camera (focal length, principal point, distortion): the focal length is
        then fixed.
    flux : array_like, shape (N,), optional
        Brightness of each star, to order them.
    epoch : astropy.time.Time or float, optional
        Epoch of the catalog positions (Julian year, TDB); default J2000.0.
    method : str
        The matcher (:data:`startrack.identify.registry.MATCHERS`): "quads", four-star patterns
        (the default; any FOV knowledge); the seeds' matchers on the star-pair directory, which
        need a FOV known to 5 % or a camera ("pyramid", "angle", "triangle-planar",
        "triangle-spherical", "nvertex-3", "nvertex-4", "nvertex-5", "van-bezooijen"); or
        "overlay", which needs a prior attitude. See ``docs/identification.md``.
    options : dataclass, optional
        Settings of the chosen matcher (``MatcherOptions`` for "quads", ``PyramidOptions`` for
        "pyramid", and so on).
    prior_rot_cam_from_icrs : Rotation, optional
        Prior attitude for the "overlay" matcher.
    prior_sigma_deg : float
        Its 1-sigma uncertainty per axis (degrees, up to 10).

    Returns
    -------
    AttitudeSolution
        ``status`` OK with the attitude, covariance, matches and residuals; otherwise
        TOO_FEW_STARS, NO_MATCH or TIMEOUT with a reason. ``solve_time_s`` excludes loading the
        pattern database (done once per process).

    Raises
    ------
    InvalidInputError
        For NaN or out-of-frame coordinates, a bad image size or field of view.
    """
    if method not in MATCHERS:
        raise InvalidInputError(f"method must be one of {', '.join(MATCHERS)}, got {method!r}")
    problem = replace(_problem(x, y, width, height, fov_deg, fov_range_deg, camera, flux, epoch),
                      prior_rot=prior_rot_cam_from_icrs, prior_sigma_deg=prior_sigma_deg)
    matcher, stars = prepare_matcher(method, problem)  # loads (or builds) the database first
    t0 = time.perf_counter()
    outcome = matcher(options)
    if outcome.candidate is None:
        return AttitudeSolution(status=outcome.status, reason=outcome.reason,
                                solve_time_s=time.perf_counter() - t0)
    return _solution(problem, stars, outcome.candidate, t0)


def solve_image(image, *, fov_deg: float | None = None, fov_range_deg: tuple[float, float] | None = None,
                camera: Camera | None = None, epoch=None, channel: str | int | None = None,
                detector=None, method: str = "quads", options: object | None = None) -> AttitudeSolution:
    """Lost-in-space attitude of an image: read, detect, solve.

    Parameters
    ----------
    image : path, ndarray or startrack.io.Image
        A FITS, PNG, JPEG or TIFF file, or a 2-D (or colour) array in counts.
    fov_deg, fov_range_deg, camera, epoch, method, options
        As in :func:`solve_stars`.
    channel : str or int, optional
        Colour channel to use: 'r', 'g' or 'b' (default: R + G + B; see :mod:`startrack.io.channels`).
    detector : startrack.detect.StarDetector, optional
        Detection settings (default: :func:`startrack.detect.detect`'s).

    Returns
    -------
    AttitudeSolution
        With ``detections`` (the stars found, brightest first; ``matches.det_index`` indexes
        them). ``solve_time_s`` covers detection and identification, not reading the file nor
        what a process does once (loading the pattern database and the compiled search).
    """
    from .detect import StarDetector
    from .io import Image, read_image

    img = image if isinstance(image, Image) else read_image(image, channel=channel)
    t0 = time.perf_counter()
    found = (detector or StarDetector()).detect(img.data)
    detect_s = time.perf_counter() - t0
    height, width = img.data.shape[:2]
    if camera is not None and (camera.width, camera.height) != (width, height):
        raise InvalidInputError(f"the camera is {camera.width} x {camera.height} px but the image is "
                                f"{width} x {height} px")
    solution = solve_stars(found.x, found.y, width=width, height=height, fov_deg=fov_deg,
                           fov_range_deg=fov_range_deg, camera=camera, epoch=epoch, method=method,
                           options=options)
    return replace(solution, solve_time_s=detect_s + solution.solve_time_s, detections=found)
